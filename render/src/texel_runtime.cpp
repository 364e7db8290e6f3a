// See texel_runtime.h.
#include "texel_runtime.h"

#include <vtex/core/error.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/octree/volume.h>
#include <vtex/render/source_visibility.h>

#include "footprint.h"
#include "near_shadow_table.h"
#include "own_share.h"

#include <tbb/task_arena.h>

#define XXH_INLINE_ALL
#include <xxhash.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <mutex>
#include <optional>
#include <string>

namespace vtex::render::detail {
namespace {

// The faithful levels (render::faithfulLevels), measured from the coarsest level finer and
// stopping at the first level past the run, so that a render does not read a lazily opened
// texel's finest levels (the bulk of its file) only to measure them.
FaithfulLevels measureFaithfulLevels(const octree::ChordMedium& medium, const octree::ChordVisibility& visible, double tau,
                                     double tolerance) {
    int coarsest = -1;
    const auto chords = octree::measureChordTransmittance(
        medium, visible, tau, kLoadChords, 1, [&](std::size_t level, const octree::ChordTransmittance& c) {
            const bool within = std::abs(c.error()) <= tolerance;
            if (within && coarsest < 0) coarsest = int(level);
            return coarsest >= 0 && !within;
        });
    return faithfulLevels(chords, tolerance);
}

// What the lit fractions (octree::measureLitFractions, kLoadChords, as the faithful levels are
// measured with) decide for fitted levels: the shadow levels and the hybrid's mesh level.
struct MeasuredLighting {
    std::vector<int> shadowLevels;  ///< TexelRuntime::shadowLevels
    int meshLevel = 0;              ///< TexelRuntime::meshLevel
};

}  // namespace

// The shadow level per footprint level f below the coarsest faithful level F (TexelRuntime::
// shadowLevels). The rule without the fit takes F, because the unfitted levels coarser than it
// are too opaque; fitted, they are not, and a dense texel's fine voxels darken the leaves they
// stand for instead (docs/render.md, "Shadows at the level that lights what is seen"). So each
// level l from f to F is judged by its lit fraction (camera level f + 1: a shadow's cone is
// twice its camera ray's) against the mesh's, and the levels within `margin` of the best, which
// the measurement cannot tell apart, are ties. Ties are settled by cost: among those a query
// reads from the near table (l ≤ tableLevel: a look-up each, whatever the level) the finest,
// nearest F as the rule without the fit; where none is, the coarsest, since past the table every
// query marches, and each level finer doubles its voxels (fur at 256³, F = 8, in the bush field's
// middle view: 10.8 s and 12.7 % too dark with every shadow at 8, 2.6 s and 8.4 % with the ties
// settled so; `PATTERN=fur bench/bush_field.sh`, docs/error-vs-time.md).
std::vector<int> shadowLevelsFrom(const octree::LitFractions& lit, int coarsest, double margin, int tableLevel) {
    std::vector<int> levels;
    for (std::size_t f = 0; f < std::size_t(std::max(coarsest, 0)) && f + 1 < lit.volume.size(); ++f) {
        const auto error = [&](std::size_t l) { return std::abs(lit.error(f + 1, l)); };
        double best = std::numeric_limits<double>::infinity();
        for (std::size_t l = f; l <= std::size_t(coarsest); ++l) best = std::min(best, error(l));
        int cheap = -1, coarsestTie = -1;
        for (std::size_t l = f; l <= std::size_t(coarsest); ++l) {
            if (!(error(l) <= best + margin)) continue;  // NaN (a pair not measured) is no tie
            if (coarsestTie < 0) coarsestTie = int(l);
            if (int(l) <= tableLevel) cheap = int(l);
        }
        levels.push_back(cheap >= 0 ? cheap : coarsestTie >= 0 ? coarsestTie : coarsest);
    }
    return levels;
}

namespace {

// The hybrid's mesh level (docs/render.md, "Mesh where the volume is not faithful"): the finest
// faithful level, unless the lighting ends the volume sooner. Camera level c, lit through the
// shadow level its cone takes (shadowLevelFor(c − 1)), is off the mesh's lit fraction by e(c):
// coarse levels light too much (a voxel spreads a clump's shadow thin), fine ones too little (a
// voxel shadows the leaves it stands for, the more so the denser the texel: the 20 000-leaf bush's
// levels 7 and 8, −0.08 and −0.13 of a lit fraction of 0.45, were its near view's −23 %; printed
// by bench/lit_fractions.cpp). Among the faithful levels, the volume keeps the one lit best, c*,
// and finer ones while |e| stays within `margin` of |e(c*)|; the mesh takes over from the first
// that does not.
int meshLevelFrom(const octree::LitFractions& lit, const std::vector<int>& shadowLevels, const FaithfulLevels& faithful,
                  double margin) {
    const auto error = [&](int c) {
        const int shadow = TexelRuntime::shadowLevelOf(shadowLevels, faithful.coarsest, c - 1);
        return std::abs(lit.error(std::size_t(c), std::size_t(shadow)));
    };
    const int first = std::max(faithful.coarsest, 1), last = std::min(faithful.finest, int(lit.volume.size()) - 1);
    if (first > last) return faithful.finest;
    int best = first;
    for (int c = first + 1; c <= last; ++c)
        if (error(c) < error(best)) best = c;
    for (int c = best + 1; c <= last; ++c)
        if (error(c) > error(best) + margin) return c - 1;
    return faithful.finest;
}

MeasuredLighting measureLighting(const octree::ChordMedium& medium, const SourceBvh& source, const octree::ChordVisibility& visible,
                                 double tau, const std::vector<double>& scales, const std::vector<double>& ownShares,
                                 const FaithfulLevels& faithful) {
    const octree::ChordFirstHit hit = [&](const Vec3& a, const Vec3& b) -> std::optional<double> {
        if (const auto h = source.intersect(a, b, 0)) return h->s;
        return std::nullopt;
    };
    // Up to the coarsest faithful level every pair (the shadow levels' choice); finer camera
    // levels c only with the shadow level they take, c − 1 (meshLevelFrom).
    const std::size_t coarsest = std::size_t(std::max(faithful.coarsest, 0));
    const std::size_t finest = std::max(std::size_t(std::max(faithful.finest, 0)), coarsest);
    const octree::LitPairs wanted = [&](std::size_t c, std::size_t l) { return l <= coarsest || l + 1 == c; };
    // The volume's shadow rays as the renderer's from a lit voxel: its own voxel less the piece it lights.
    const octree::LitFractions lit =
        octree::measureLitFractions(medium, hit, visible, tau, scales, finest, kLoadChords, 1, wanted, ownShares);
    const double margin = 2 * lit.meshStandardError();
    MeasuredLighting out{shadowLevelsFrom(lit, faithful.coarsest, margin, NearShadowTable::kMaxLevel), faithful.finest};
    out.meshLevel = meshLevelFrom(lit, out.shadowLevels, faithful, margin);
    return out;
}

// Everything a texel's load measures against its source (measureSource), with the render's
// options: the faithful levels as measured (uncapped), then with the hybrid on no level finer
// than kFinestMarchedLevel is fitted or lit, nor taken as the mesh level (marchedLevels).
octree::SourceMeasures measureWith(const octree::Octree& tree, const SourceBvh& source, double tau, double tolerance,
                                   bool hybrid, bool fitLevels) {
    const octree::ChordVisibility visible = [&](const Vec3& a, const Vec3& b) { return !source.occluded(a, b, 0); };
    // One medium for the three measures: they share its dense levels (chord_medium.h).
    const octree::ChordMedium medium(tree);
    const FaithfulLevels measured = measureFaithfulLevels(medium, visible, tau, tolerance);
    const FaithfulLevels faithful = hybrid ? marchedLevels(measured) : measured;
    octree::SourceMeasures m;
    m.version = sourceMeasuresVersion();
    m.tau = tau;
    m.tolerance = tolerance;
    m.faithfulCoarsest = measured.coarsest;
    m.faithfulFinest = measured.finest;
    m.meshLevel = faithful.finest;
    // Every level a shadow may march: with the hybrid none finer than the mesh level.
    m.ownShares = measureOwnShares(source, hybrid ? faithful.finest : int(tree.levels.size()) - 1);
    if (fitLevels) {
        // Measured before the fit, the faithful levels keep saying where the volume's chords
        // differ from the mesh's per chord, which a scale per level does not change.
        // kLevelFitChords: on a texel of clustered discs a fit then lets through what the mesh
        // does within 0.003 on other chords (ShellChords.AFittedLevelLetsThroughWhatTheMeshDoesOnOtherChords).
        // With the hybrid on, no level finer than the mesh level (≤ `faithful.finest`) is
        // marched, by camera or shadow rays (volumeUnderMesh, TexelRuntime::shadowLevelFor).
        const std::uint32_t finest = hybrid ? std::uint32_t(faithful.finest) : 30u;
        for (const octree::ShellChordFit& fit : octree::fitShellChords(medium, visible, tau, kLevelFitChords, 1, finest))
            m.levelScales.push_back(fit.scale);
        const MeasuredLighting lighting = measureLighting(medium, source, visible, tau, m.levelScales, m.ownShares, faithful);
        m.shadowLevels.assign(lighting.shadowLevels.begin(), lighting.shadowLevels.end());
        m.meshLevel = lighting.meshLevel;
    }
    return m;
}

// The runtime's levels from the measures: shadows keep to the coarsest faithful level, the
// hybrid traces the mesh past the mesh level.
void applyMeasures(TexelRuntime& t, const octree::SourceMeasures& m, bool hybrid) {
    const FaithfulLevels measured{m.faithfulCoarsest, m.faithfulFinest};
    t.coarsestShadowLevel = (hybrid ? marchedLevels(measured) : measured).coarsest;
    t.levelScale = m.levelScales;
    t.ownShare = m.ownShares;
    t.shadowLevels.assign(m.shadowLevels.begin(), m.shadowLevels.end());
    if (hybrid) {
        t.meshLevel = m.meshLevel;
        t.faithfulFinest = m.faithfulFinest;
    }
}

// Whether `file` holds the bytes of XXH3 `hash`; false when it cannot be read (the mesh's
// reading then reports why, naming the scene's key).
bool sameFile(const std::filesystem::path& file, std::uint64_t hash) {
    try {
        return sourceFileHash(file) == hash;
    } catch (const InputError&) {
        return false;
    }
}

}  // namespace

struct SourceHandle::State {
    octree::VolumeInfo volume;
    std::function<Mesh()> read;
    std::once_flag once;
    std::atomic<const SourceBvh*> ready{nullptr};
    Mesh mesh;  // SourceBvh keeps a reference to it
    std::unique_ptr<const SourceBvh> bvh;

    void build(Mesh m) {
        mesh = std::move(m);
        bvh = std::make_unique<const SourceBvh>(*mesh, volume);
        ready.store(bvh.get(), std::memory_order_release);
    }
};

SourceHandle::SourceHandle(Mesh mesh, const octree::VolumeInfo& volume) : mState(std::make_unique<State>()) {
    mState->volume = volume;
    mState->build(std::move(mesh));
}

SourceHandle::SourceHandle(std::function<Mesh()> read, const octree::VolumeInfo& volume)
    : mState(std::make_unique<State>()) {
    mState->volume = volume;
    mState->read = std::move(read);
}

SourceHandle::SourceHandle() = default;
SourceHandle::SourceHandle(SourceHandle&&) noexcept = default;
SourceHandle& SourceHandle::operator=(SourceHandle&&) noexcept = default;
SourceHandle::~SourceHandle() = default;

const SourceBvh& SourceHandle::operator*() const {
    if (const SourceBvh* bvh = mState->ready.load(std::memory_order_acquire)) return *bvh;
    // Read inside a pixel's task: isolated, so that the reading's and Embree's own parallel loops
    // cannot take another pixel's task on this thread, which would wait here for itself.
    std::call_once(mState->once, [&] { tbb::this_task_arena::isolate([&] { mState->build(mState->read()); }); });
    return *mState->ready.load(std::memory_order_acquire);
}

const ingest::TriangleMesh& SourceHandle::mesh() const {
    static_cast<void>(**this);  // read first, if it was not
    return *mState->mesh;
}

bool SourceHandle::loaded() const { return mState && mState->ready.load(std::memory_order_acquire); }

std::vector<double> finestRequestedLevels(const Scene& scene, const SceneGeometry& geometry, double coneSpread,
                                          const RenderOptions& options) {
    const double lodBias = options.lodBias;
    const bool directional = std::any_of(scene.lights.begin(), scene.lights.end(),
                                         [](const Light& l) { return l.type == LightType::Directional; });
    const int lattice = options.approximations.shadowCacheResolution;
    const double nodeLevel = directional && lattice > 0 ? std::log2(double(lattice)) + 1 - lodBias
                                                        : -std::numeric_limits<double>::infinity();
    std::vector<double> finest(scene.texels.size(), -std::numeric_limits<double>::infinity());
    const Vec3 lo = geometry.tracer->boundsLo(), hi = geometry.tracer->boundsHi();
    const Vec3 eye = scene.camera.position;
    const double distance = (eye - eye.cwiseMax(lo).cwiseMin(hi)).norm();
    const PrimTable& prims = geometry.tracer->prims();
    std::optional<Prim> scratch;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        if (!prims.textured(i)) continue;
        const Prim& prim = prims.at(i, scratch);
        const double scale = prim.cell.size() * std::cbrt(std::max(1.0, 1.0 / prim.map.areaScale()));
        const double level = distance > 0 && coneSpread > 0 ? -std::log2(coneSpread * distance / scale) - lodBias
                                                            : std::numeric_limits<double>::infinity();
        double& texel = finest[std::size_t(geometry.surfaces[std::size_t(prim.surface)].texel)];
        texel = std::max({texel, nodeLevel, std::isnan(level) ? std::numeric_limits<double>::infinity() : level});
    }
    return finest;
}

std::vector<TexelRuntime> loadTexels(const Scene& scene, const RenderOptions& options,
                                     const std::vector<double>& finestRequested) {
    std::vector<TexelRuntime> texels(scene.texels.size());
    for (const std::size_t index : usedTexels(scene)) {
        TexelRuntime& t = texels.at(index);
        if (t.volume) continue;
        const TexelDef& def = scene.texels[index];
        auto tree = loadTexelVolume(scene, index);
        tree->loadLevels(0);
        if (tree->levels.empty() || tree->levels[0].empty())
            throw InputError(def.volume, "octree has no root");
        t.tau = def.tau;
        t.material = def.material;
        // With a source, the levels the volume is faithful at are measured (one pass of chords):
        // shadows keep to them, and the hybrid traces the mesh past the finest of them. What
        // `vtex build --source` stored in the texel is taken instead when it was measured for
        // this source, τ and tolerance with the default options (measuresApply): then the load
        // reads none of the levels the measure would have (a texel faithful to its finest
        // level: all of them).
        if (def.sourceData || !def.source.empty()) {
            const octree::SourceMeasures* stored =
                options.hybrid && options.fitLevels && tree->measures &&
                        measuresApply(*tree->measures, def.tau, options.hybridTolerance)
                    ? &*tree->measures
                    : nullptr;
            // No ray can ask for the mesh level, and the scene's source file holds the bytes the
            // record was measured from: the mesh is read only if a ray needs it after all.
            const bool meshUnasked = index < finestRequested.size() && stored && finestRequested[index] <= stored->meshLevel;
            if (meshUnasked && !def.sourceData && stored->fileHash != 0 && sameFile(def.source, stored->fileHash)) {
                t.measuresStored = true;
                applyMeasures(t, *stored, true);
                // The runtimes live within the render of `scene` (renderScene), so the reference holds.
                t.source = SourceHandle([&scene, index] { return loadTexelSource(scene, index); }, tree->info.source);
            } else {
                // Another file (or a mesh given in memory) may still be the record's geometry.
                SourceHandle source(loadTexelSource(scene, index), tree->info.source);
                t.measuresStored = stored && stored->geometryHash == sourceGeometryHash(source.mesh());
                applyMeasures(t,
                              t.measuresStored ? *stored
                                               : measureWith(*tree, *source, def.tau, options.hybridTolerance,
                                                             options.hybrid, options.fitLevels),
                              options.hybrid);
                if (options.hybrid) t.source = std::move(source);
            }
        }
        t.volume = std::make_unique<const MarchVolume>(std::move(tree));
    }
    return texels;
}

}  // namespace vtex::render::detail

namespace vtex::render {

std::uint32_t sourceMeasuresVersion() {
    // The rules' revision (raise it when what measureWith measures changes otherwise), then the
    // constants the measures depend on: a record from another build of them is measured again.
    constexpr int kRevision = 2;  // 2: the own shares
    const std::string recipe = std::to_string(kRevision) + " " + std::to_string(kLoadChords) + " " +
                               std::to_string(kLevelFitChords) + " " + std::to_string(kFinestMarchedLevel) + " " +
                               std::to_string(detail::NearShadowTable::kMaxLevel);
    return std::uint32_t(XXH3_64bits(recipe.data(), recipe.size()));
}

std::uint64_t sourceGeometryHash(const ingest::TriangleMesh& mesh) {
    XXH3_state_t state;
    XXH3_INITSTATE(&state);
    XXH3_64bits_reset(&state);
    const std::uint64_t counts[2] = {mesh.positions.size(), mesh.triangles.size()};
    XXH3_64bits_update(&state, counts, sizeof counts);
    for (const Eigen::Vector3f& p : mesh.positions) XXH3_64bits_update(&state, p.data(), 3 * sizeof(float));
    XXH3_64bits_update(&state, mesh.triangles.data(), mesh.triangles.size() * sizeof(mesh.triangles[0]));
    return XXH3_64bits_digest(&state);
}

octree::SourceMeasures measureSource(const octree::Octree& tree, const ingest::TriangleMesh& source, double tau,
                                     double tolerance, const std::filesystem::path& file) {
    const detail::SourceBvh bvh(source, tree.info.source);
    octree::SourceMeasures m = detail::measureWith(tree, bvh, tau, tolerance, true, true);
    m.geometryHash = sourceGeometryHash(source);
    if (!file.empty()) m.fileHash = sourceFileHash(file);
    return m;
}

std::uint64_t sourceFileHash(const std::filesystem::path& file) {
    const std::string bytes = octree::readFileBytes(file);
    return XXH3_64bits(bytes.data(), bytes.size());
}

bool measuresApply(const octree::SourceMeasures& stored, double tau, double tolerance) {
    return stored.version == sourceMeasuresVersion() && stored.tau == tau && stored.tolerance == tolerance;
}

}  // namespace vtex::render

