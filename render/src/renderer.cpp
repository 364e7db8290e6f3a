// The texel renderer (DESIGN.md, "Rendering"; Neyret 1994 §4 for the ray tracing of texels).
//
// A camera ray is traced through Embree against plain faces (opaque bilinear patches) and texel
// cells (trilinear shells). Inside a cell the span between entry and exit is a straight segment
// in reference space (the paper's mild-deformation assumption); its footprint picks two octree
// levels (GigaVoxels' cone rule), each marched front to back, and their results are blended.
// The cell's bottom face (w = 0) is the opaque base surface, drawn with the face's material.
#include <vtex/render/renderer.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/memory_budget.h>
#include <vtex/render/texel_march.h>

#include "footprint.h"
#include "frame.h"
#include "shadow_queries.h"
#include "span_march.h"
#include "texel_runtime.h"
#include "tracer.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

namespace vtex::render {

ApproximationBudget ApproximationBudget::exact() {
    ApproximationBudget b;
    b.shareShadowRays = false;
    b.shadowCacheResolution = 0;
    b.chainLatticeNodes = false;
    b.nearShadowTable = false;
    b.blendCutoff = 0;
    b.lightingReuseWeight = 0;
    b.exactFloorShadowAbove = 0;
    b.floorShadowTable = false;
    b.fieldShadowVolume = false;
    b.shadowRefresh = 1;
    return b;
}

bool ApproximationBudget::isExact() const { return *this == exact(); }

std::string ApproximationBudget::key() const {
    std::ostringstream k;
    k.precision(17);
    k << "share_shadow_rays " << shareShadowRays << " shadow_cache_resolution " << shadowCacheResolution
      << " chain_lattice_nodes " << chainLatticeNodes << " near_shadow_table " << nearShadowTable << " blend_cutoff "
      << blendCutoff << " lighting_reuse_weight " << lightingReuseWeight << " exact_floor_shadow_above "
      << exactFloorShadowAbove << " floor_shadow_table " << floorShadowTable << " field_shadow_volume " << fieldShadowVolume
      << " shadow_refresh " << shadowRefresh;
    return k.str();
}

double RenderStats::meanLevel() const {
    double sum = 0, weight = 0;
    for (std::size_t l = 0; l < levelHistogram.size(); ++l) {
        sum += double(l) * levelHistogram[l];
        weight += levelHistogram[l];
    }
    return weight > 0 ? sum / weight : -1;
}

namespace {

using detail::Counters;
using detail::Hit;
using detail::Prim;
using detail::SurfaceRuntime;
using detail::Tracer;
using detail::bilerp;
using detail::entryCoords;
using detail::geometricNormal;
using detail::lightAt;
using detail::shadingNormal;

using detail::kTransmittanceCutoff;
using detail::localScale;
using detail::ShadowQueries;
using detail::SpanContext;
using detail::SpanMarcher;
using detail::SpanResult;
using detail::TexelRuntime;
using detail::tile;

double patchSize(const Prim& prim) { return detail::patchSize(prim.p); }

struct PathState {
    Color radiance = Color::Zero();
    double transmittance = 1;
    double depth = 0;
    double levelSum = 0, levelWeight = 0;
    bool depthSet = false;
    void noteOpacity(double t, double before, double after) {
        if (!depthSet && before >= 0.5 && after < 0.5) {
            depth = t;
            depthSet = true;
        }
    }
};

class Integrator {
public:
    Integrator(const Scene& scene, const RenderOptions& options, const Tracer& tracer,
               const std::vector<SurfaceRuntime>& surfaces, const std::vector<TexelRuntime>& texels,
               double coneSpread)
        : mScene(scene), mOptions(options), mTracer(tracer), mSurfaces(surfaces), mTexels(texels),
          mConeSpread(coneSpread) {}

    PathState radiance(const Vec3& o, const Vec3& d, Counters& counters) const {
        PathState state;
        ++counters.primary;
        double tNear = 0;
        detail::SpanCache cache;
        for (int bounce = 0; bounce < 4096 && state.transmittance > kTransmittanceCutoff; ++bounce) {
            const auto hit = mTracer.trace(o, d, tNear, std::numeric_limits<double>::infinity(), &cache);
            if (!hit) break;
            std::optional<Prim> scratch;
            const Prim& prim = mTracer.prims().at(std::size_t(hit->prim), scratch);
            const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
            if (!prim.textured) {
                const Vec3 x = bilerp(prim.p, hit->u, hit->v);
                const Vec3 ng = geometricNormal(prim.p, hit->u, hit->v, prim.n);
                const Vec3 n = shadingNormal(prim.n, hit->u, hit->v, ng);
                opaque(state, hit->t, shadeSurface(x, n, ng, -d, surface.material, patchSize(prim), hit->t, counters));
                break;
            }
            const CellSpan& span = hit->span;
            if (span.faceIn == 0 && hit->t <= span.tIn) {  // the base surface, seen from below or beside
                opaque(state, hit->t, shadeFloor(prim, surface, span.rIn, d, hit->t, state.transmittance, counters));
                break;
            }
            const auto rIn = entryCoords(prim, *hit, o, d, -1, Vec3::Zero());
            if (rIn) marchSpan(prim, surface, *rIn, span.rOut, hit->t, span.tOut, d, state, counters);
            if (state.transmittance <= kTransmittanceCutoff) break;
            if (span.faceOut == 0) {
                opaque(state, span.tOut, shadeFloor(prim, surface, span.rOut, d, span.tOut, state.transmittance, counters));
                break;
            }
            tNear = span.tOut;
        }
        return state;
    }

    const ShadowQueries& shadows() const { return mShadows; }

private:
    static void opaque(PathState& state, double t, const Color& radiance) {
        state.radiance += state.transmittance * radiance;
        state.noteOpacity(t, state.transmittance, 0);
        state.transmittance = 0;
    }

    // The base surface at cell coordinates r, seen through transmittance `seenThrough`. Its
    // shadows (ShadowQueries::floorShadow): the floor table where its cell takes it; otherwise
    // exact rays, except where it is seen through less than RenderOptions::exactFloorShadowAbove:
    // there the cell's transmittance lattice answers (as it does for voxels), which moves the
    // pixel by at most seenThrough × the floor's direct light.
    Color shadeFloor(const Prim& prim, const SurfaceRuntime& surface, const Vec3& r, const Vec3& d, double t,
                     double seenThrough, Counters& counters) const {
        const Vec3 x = prim.cell.map(Vec3(r.x(), r.y(), 0));
        const auto bottom = prim.cell.faceCorners(0);
        const Vec3 ng = geometricNormal(bottom, r.x(), r.y(), prim.n);
        const Vec3 n = shadingNormal(prim.n, r.x(), r.y(), ng);
        const double scale = std::min(surface.height, patchSize(prim));
        const bool dim = seenThrough < mOptions.approximations.exactFloorShadowAbove;
        return detail::shadePhong(mScene.lights, x, n, ng, -d, surface.material, Color::Ones(), scale,
                                  [&](const Vec3& origin, const Vec3& l, double distance) {
                                      return mShadows.floorShadow(prim, r, origin, l, distance, mConeSpread * t, dim, counters);
                                  });
    }

    // An opaque surface point: exact shadow rays.
    Color shadeSurface(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& view, const Material& m, double scale,
                       double t, Counters& counters) const {
        return detail::shadePhong(mScene.lights, x, n, ng, view, m, Color::Ones(), scale,
                                  [&](const Vec3& origin, const Vec3& l, double distance) {
                                      return mShadows.shadowTransmittance(origin, l, distance, mConeSpread * t, nullptr,
                                                                          Vec3::Zero(), counters);
                                  });
    }

    // A camera ray's span through a texel cell: the level blend of GigaVoxels' cone rule (two
    // levels marched and blended, a weight under the cut-off skipped) and the mesh/volume hybrid
    // around it (the source mesh with the share its footprint gives), composited into the path.
    void marchSpan(const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, double tIn,
                   double tOut, const Vec3& d, PathState& state, Counters& counters) const {
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        const double tMid = 0.5 * (tIn + tOut);
        const double scale = localScale(prim, 0.5 * (rIn + rOut));
        const double footprint = mConeSpread * tMid / scale;  // the cone's width, reference units
        const int maxLevel = texel.volume->maxLevel();
        LevelChoice choice = chooseLevel(footprint, mOptions.lodBias, maxLevel);
        const Vec3 p0 = tile(rIn, prim), p1 = tile(rOut, prim);
        const double length = (p1 - p0).norm();
        if (!(length > 0) || !std::isfinite(length)) return;
        ++counters.segments;
        // A blend weight below blendCutoff goes to the other level, which is then the only one
        // marched: the image moves by at most that weight times the difference of the two
        // levels' results (bounded by the test SkippedBlendLevelsMatchTheFullBlend). The same
        // cut-off for the mesh's share.
        const double cutoff = mOptions.approximations.blendCutoff;
        const auto cut = [cutoff](double w) { return w > 0 && w < cutoff ? 0.0 : w > 1 - cutoff ? 1.0 : w; };
        const double meshWeight = cut(texel.meshWeight(choice.requested));
        // Under the mesh's share the volume is the mesh level L alone: the span is (1 − w)·V_L +
        // w·mesh, continuous at both ends of the blend (docs/render.md, "Blend").
        choice = detail::volumeUnderMesh(choice, texel.meshLevel);
        const double fineWeight = cut(choice.fineWeight);
        counters.mesh += meshWeight;
        if (meshWeight >= 1) {  // the mesh alone: none of the volume's per-span set-up
            compositeSpan(traceSourceSpan(prim, texel, p0, p1, tIn, tOut, d, choice.requested, footprint, counters), choice.level,
                          tMid, state);
            return;
        }
        SpanContext span(mScene, mOptions, mShadows, prim, surface, texel, rIn, rOut, tIn, tOut, scale,
                         state.transmittance, choice.coarse);
        if (counters.histogram.size() < std::size_t(maxLevel + 1)) counters.histogram.resize(std::size_t(maxLevel + 1), 0.0);
        if (fineWeight < 1) counters.histogram[std::size_t(choice.coarse)] += (1 - fineWeight) * (1 - meshWeight);
        if (fineWeight > 0) counters.histogram[std::size_t(choice.fine)] += fineWeight * (1 - meshWeight);
        SpanResult result;
        if (fineWeight >= 1) {
            result = mMarcher.march(span, choice.fine, false, 1.0, counters);
        } else {
            // The second (fine) march of a blend takes the first's shadow queries taken within
            // one coarse voxel (shareShadowRays): the origin moves by at most that, bounded by the
            // test SharedShadowRaysMatchPerLevelShadowRays. Without a second march (its weight
            // cut) nothing is recorded.
            const bool share = mOptions.approximations.shareShadowRays && fineWeight > 0;
            result = mMarcher.march(span, choice.coarse, share, 1 - fineWeight, counters);
            if (fineWeight > 0) blend(result, mMarcher.march(span, choice.fine, false, fineWeight, counters), fineWeight);
        }
        if (meshWeight > 0)
            blend(result, traceSourceSpan(prim, texel, p0, p1, tIn, tOut, d, choice.requested, footprint, counters), meshWeight);
        compositeSpan(result, choice.level, tMid, state);
    }

    // result ← (1 − w)·result + w·other, colour and transmittance alike.
    static void blend(SpanResult& result, const SpanResult& other, double w) {
        result.radiance = (1 - w) * result.radiance + w * other.radiance;
        result.transmittance = (1 - w) * result.transmittance + w * other.transmittance;
    }

    static void compositeSpan(const SpanResult& result, double level, double tMid, PathState& state) {
        const double before = state.transmittance;
        state.radiance += before * result.radiance;
        state.transmittance = before * result.transmittance;
        const double absorbed = before - state.transmittance;
        state.levelSum += absorbed * level;
        state.levelWeight += absorbed;
        state.noteOpacity(tMid, before, state.transmittance);
    }

    // The span through the texel's source mesh instead of its volume (the hybrid): the first
    // triangle on the tiled reference-space segment p0 → p1, opaque and two-sided, shaded as the
    // reference renderer shades it (the texel's material, the mesh's albedo, the normal taken
    // to the world by the inverse transpose of the tiled map's Jacobian), its shadows through the
    // source meshes (tracedShadow's fromSourceHit). Where the footprint is coarser than a voxel
    // of level L + 1 (TexelRuntime::meshRaysPerAxis) the span takes k × k parallel segments on a
    // stratified grid across the footprint (`width`: the cone's at the span's middle, reference
    // units, the level was chosen from), their radiance and transmittance averaged: the
    // mesh's coverage of the footprint rather than one point of it. Segments that leave the
    // cell's side go on in the tiled copy beside it, which is the neighbour's on a flat base (the
    // mild-deformation assumption of the march); spans are composited as volume spans are, so
    // what hides what between two spans is that of their coverages.
    SpanResult traceSourceSpan(const Prim& prim, const TexelRuntime& texel, const Vec3& p0, const Vec3& p1, double tIn,
                               double tOut, const Vec3& d, double requested, double width, Counters& counters) const {
        const int k = texel.meshRaysPerAxis(requested);
        if (k <= 1) return traceSourceSegment(prim, texel, p0, p1, tIn, tOut, d, counters);
        const Vec3 axis = (p1 - p0).normalized();
        const Vec3 u = axis.unitOrthogonal(), v = axis.cross(u);
        SpanResult sum{Color::Zero(), 0.0};
        for (int i = 0; i < k; ++i)
            for (int j = 0; j < k; ++j) {
                const Vec3 offset = width * (((i + 0.5) / k - 0.5) * u + ((j + 0.5) / k - 0.5) * v);
                const SpanResult r = traceSourceSegment(prim, texel, p0 + offset, p1 + offset, tIn, tOut, d, counters);
                sum.radiance += r.radiance;
                sum.transmittance += r.transmittance;
            }
        const double n = double(k * k);
        return {sum.radiance / n, sum.transmittance / n};
    }
    SpanResult traceSourceSegment(const Prim& prim, const TexelRuntime& texel, const Vec3& p0, const Vec3& p1,
                                  double tIn, double tOut, const Vec3& d, Counters& counters) const {
        const auto hit = texel.source->intersect(p0, p1, 0);
        if (!hit) return {};
        const detail::SourcePoint p = detail::sourcePoint(prim, p0 + hit->s * (p1 - p0), hit->normal, d);
        const double t = tIn + hit->s * (tOut - tIn);
        // A hit past the cell's side (an offset segment's) has no cell the caller knows.
        const bool inCell = p.cell.x() >= 0 && p.cell.x() <= 1 && p.cell.y() >= 0 && p.cell.y() <= 1;
        const Color radiance = detail::shadePhong(
            mScene.lights, p.world, p.normal, p.normal, -d, texel.material, hit->albedo, p.scale,
            [&](const Vec3& origin, const Vec3& l, double distance) {
                return mShadows.tracedShadow(origin, l, distance, mConeSpread * t, inCell ? prim.index : -1, p.cell,
                                             counters, true);
            });
        return {radiance, 0.0};
    }

    const Scene& mScene;
    const RenderOptions& mOptions;
    const Tracer& mTracer;
    const std::vector<SurfaceRuntime>& mSurfaces;
    const std::vector<TexelRuntime>& mTexels;
    double mConeSpread;
    ShadowQueries mShadows{mScene, mOptions, mTracer, mSurfaces, mTexels};
    SpanMarcher mMarcher{mScene, mOptions, mShadows, mConeSpread};
};

// The shadow lattices' cap (light_cache.h) and the near and floor tables' (near_shadow_table.h,
// floor_shadow_table.h) where a texel can meet a directional light: all are allocated as cells
// are first queried, so the cap, not the use, is what is known before the render.
std::uint64_t latticeMemoryCap(const Scene& scene, const RenderOptions& options) {
    if (options.approximations.shadowCacheResolution <= 0) return 0;
    const auto lights = std::uint64_t(std::count_if(scene.lights.begin(), scene.lights.end(),
                                                    [](const Light& l) { return l.type == LightType::Directional; }));
    if (lights == 0 || usedTexels(scene).empty()) return 0;
    const std::uint64_t tables = (options.approximations.nearShadowTable ? lights * detail::NearShadowTable::kBytesPerLight : 0) +
                                 (options.approximations.floorShadowTable ? lights * detail::FloorShadowTable::kBytesPerLight : 0) +
                                 (options.approximations.fieldShadowVolume ? lights * detail::FloorShadowTable::kVolumeBytesPerLight : 0);
    return std::uint64_t(detail::LightTransmittanceCache::kMaxNodes) * sizeof(float) + tables;
}

}  // namespace

std::uint64_t estimateRenderMemory(const Scene& scene, const RenderOptions& options) {
    return detail::imageAndSceneMemory(scene, options) + latticeMemoryCap(scene, options);
}

namespace {

// renderScene in the arena of withThreads.
RenderResult renderSceneInArena(const Scene& scene, const RenderOptions& options, Progress& progress) {
    const auto loadStart = std::chrono::steady_clock::now();
    RenderResult result;
    const detail::ImageFrame frame = detail::imageFrame(scene, options);
    const int width = frame.width, height = frame.height;
    const int strata = std::max(1, int(std::ceil(std::sqrt(double(std::max(options.spp, 1))))));
    checkMemoryEstimate(scene.file, "rendering " + std::to_string(width) + "x" + std::to_string(frame.rows()),
                        estimateRenderMemory(scene, options), options.maxMemoryBytes);

    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    const double coneSpread = detail::coneSpread(scene.camera.fovY, height, strata);
    // Texels referenced by some surface (the others are not loaded).
    const std::vector<TexelRuntime> texels = detail::loadTexels(
        scene, options, detail::finestRequestedLevels(scene, geometry, coneSpread, options));

    const detail::CameraRays camera(scene.camera, width, height);
    const Integrator integrator(scene, options, *geometry.tracer, geometry.surfaces, texels, coneSpread);
    const auto renderStart = std::chrono::steady_clock::now();
    const double loadSeconds = std::chrono::duration<double>(renderStart - loadStart).count();

    Image image(width, frame.rows(), options.aovs);
    const int threads = detail::resolveThreads(options.threads);
    std::vector<Counters> tileCounters;
    detail::renderTiles(image, frame, progress, tileCounters, [&](int x, int y, Counters& counters) {
        detail::PixelValue value;
        double depth = 0, levelSum = 0, levelWeight = 0;
        int depthCount = 0;
        for (int sy = 0; sy < strata; ++sy) {
            for (int sx = 0; sx < strata; ++sx) {
                const double px = (x + (sx + 0.5) / strata) / width;
                const double py = (y + (sy + 0.5) / strata) / height;
                const PathState s = integrator.radiance(camera.origin(), camera.direction(px, py), counters);
                value.radiance += s.radiance;
                value.alpha += 1 - s.transmittance;
                if (s.depthSet) {
                    depth += s.depth;
                    ++depthCount;
                }
                levelSum += s.levelSum;
                levelWeight += s.levelWeight;
            }
        }
        const double n = double(strata * strata);
        value.radiance /= n;
        value.alpha /= n;
        value.depth = depthCount ? depth / depthCount : 0.0;
        value.level = levelWeight > 0 ? levelSum / levelWeight : -1.0;
        return value;
    });

    const double wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - renderStart).count();
    result.stats = detail::summarize(tileCounters, geometry, threads, frame, strata * strata, wallSeconds, loadSeconds);
    for (std::size_t i = 0; i < texels.size(); ++i) {
        const TexelRuntime& t = texels[i];
        if (!t.volume) continue;
        result.stats.meshLevels.push_back(t.source ? t.meshLevel : -1.0);
        result.stats.levelScales.push_back(t.levelScale);
        result.stats.shadowLevels.push_back(t.shadowLevels);
        result.stats.ownShares.push_back(t.ownShare);
        const TexelDef& def = scene.texels[i];
        const bool sourced = def.sourceData || !def.source.empty();
        result.stats.sourceMeasures.push_back(t.measuresStored ? "stored" : sourced ? "measured" : "none");
        result.stats.sourceLoaded.push_back(t.source.loaded());
        detail::countVtoBytes(scene.texels[i], t.volume->tree(), result.stats);
    }
    result.stats.approximations = options.approximations.isExact() ? "exact" : options.approximations.key();
    result.image = std::move(image);
    result.warnings = detail::renderWarnings(scene, tileCounters);
    if (integrator.shadows().chainCut())
        result.warnings.push_back("a shadow-lattice chain crossed more than 256 cells and was cut with an exact ray where it "
                                  "had got to: the image may differ slightly with the threads or the rows rendered "
                                  "(docs/render.md, \"Shadows\")");
    return result;
}

}  // namespace

RenderResult renderScene(const Scene& scene, const RenderOptions& options, Progress& progress) {
    return detail::withThreads(options.threads, [&] { return renderSceneInArena(scene, options, progress); });
}

void writeStatsJson(const RenderStats& s, const std::filesystem::path& file) {
    AtomicOutputFile out(file);
    writeStatsJson(s, out);
    out.commit();
}

void writeStatsJson(const RenderStats& s, AtomicOutputFile& out) {
    const std::string text = formatStatsJson(s);
    out.stream().write(text.data(), std::streamsize(text.size()));
}

std::string formatStatsJson(const RenderStats& s) {
    nlohmann::json j;
    j["renderer"] = s.renderer;
    j["wall_seconds"] = s.wallSeconds;
    j["load_seconds"] = s.loadSeconds;
    j["threads"] = s.threads;
    j["width"] = s.width;
    j["height"] = s.height;
    j["spp"] = s.spp;
    // Only a partial render says which rows it made: a whole render's stats.json is as before.
    if (s.rowEnd - s.rowBegin < s.height) {
        j["row_begin"] = s.rowBegin;
        j["row_end"] = s.rowEnd;
    }
    j["faces"] = s.faces;
    j["cells"] = s.cells;
    j["rays"] = {{"primary", s.primaryRays}, {"shadow", s.shadowRays}};
    j["cell_segments"] = s.cellSegments;
    j["voxels_visited"] = s.voxelsVisited;
    j["reflectance_evaluations"] = s.reflectanceEvaluations;
    j["level_histogram"] = s.levelHistogram;
    j["vto_bytes_read"] = s.vtoBytesRead;
    j["vto_file_bytes"] = s.vtoFileBytes;
    j["mean_level"] = s.meanLevel();
    if (s.renderer == "texel") {
        j["mesh_segments"] = s.meshSegments;
        j["mesh_levels"] = s.meshLevels;
        j["level_scales"] = s.levelScales;
        j["shadow_levels"] = s.shadowLevels;
        j["own_shares"] = s.ownShares;
        j["source_measures"] = s.sourceMeasures;
        j["source_loaded"] = s.sourceLoaded;
        j["approximations"] = s.approximations;
    }
    if (s.renderer != "texel") j["reference_triangles"] = s.referenceTriangles;
    return j.dump(2) + "\n";
}

}  // namespace vtex::render
