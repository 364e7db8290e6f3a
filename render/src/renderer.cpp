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
#include <vtex/render/shading.h>
#include <vtex/render/texel_march.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/chord_transmittance.h>

#include "footprint.h"
#include "frame.h"
#include "light_cache.h"
#include "march.h"
#include "source_bvh.h"
#include "tracer.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>
#include <optional>

namespace vtex::render {

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

double patchSize(const Prim& prim) { return detail::patchSize(prim.p); }

constexpr double kTransmittanceCutoff = 1e-4;
// Shadow rays from inside a texel march one level coarser than the camera ray (a cone twice as
// wide): soft shadows need less detail than what is seen, and this halves their cost.
constexpr double kShadowConeScale = 2.0;
// Lattice steps marched exactly from a shadow query before the lattice is looked up.
constexpr double kExactLatticeSteps = 2.0;
// Shadow rays from a source-mesh hit skip this much reference space where they leave it (the
// reference renderer's gap, reference.cpp).
constexpr double kSelfIntersectionGap = 1e-5;

// Per-light state of a march: on the stack for up to 16 lights (every scene of the tests and
// benchmarks), on the heap beyond, so that every light lights every voxel.
template <class T>
class PerLight {
public:
    explicit PerLight(std::size_t n) : mData(mSmall.data()) {
        if (n > mSmall.size()) {
            mLarge.resize(n);
            mData = mLarge.data();
        } else {
            std::fill_n(mData, n, T{});  // only the lights there are: a track is 520 bytes
        }
    }
    PerLight(const PerLight&) = delete;
    PerLight& operator=(const PerLight&) = delete;
    T& operator[](std::size_t i) { return mData[i]; }
    const T& operator[](std::size_t i) const { return mData[i]; }

private:
    std::array<T, 16> mSmall;
    std::vector<T> mLarge;
    T* mData;
};

struct SpanResult {
    Color radiance = Color::Zero();
    double transmittance = 1;
};

struct TexelRuntime {
    std::unique_ptr<const MarchVolume> volume;
    double tau = 1;
    Material material;
    /// The mesh/volume hybrid (docs/render.md, "Mesh where the volume is not faithful"): the
    /// texel's source mesh, traced where a footprint asks for a level finer than `meshLevel`
    /// (blended over the next level); no source, or the hybrid off: never.
    std::shared_ptr<const ingest::TriangleMesh> sourceMesh;
    std::unique_ptr<const detail::SourceBvh> source;
    double meshLevel = std::numeric_limits<double>::infinity();
    /// The mesh's share at continuous level `requested` (LevelChoice::requested).
    double meshWeight(double requested) const {
        return source ? std::clamp(requested - meshLevel, 0.0, 1.0) : 0.0;
    }
};

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
            const Prim& prim = mTracer.prims()[std::size_t(hit->prim)];
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

private:
    static void opaque(PathState& state, double t, const Color& radiance) {
        state.radiance += state.transmittance * radiance;
        state.noteOpacity(t, state.transmittance, 0);
        state.transmittance = 0;
    }

    // The base surface at cell coordinates r, seen through transmittance `seenThrough`. Its
    // shadow rays are exact, except where it is seen through less than
    // RenderOptions::exactFloorShadowAbove: there the cell's transmittance lattice answers (as it
    // does for voxels), which moves the pixel by at most seenThrough × the floor's direct light.
    Color shadeFloor(const Prim& prim, const SurfaceRuntime& surface, const Vec3& r, const Vec3& d, double t,
                     double seenThrough, Counters& counters) const {
        const Vec3 x = prim.cell.map(Vec3(r.x(), r.y(), 0));
        const auto bottom = prim.cell.faceCorners(0);
        const Vec3 ng = geometricNormal(bottom, r.x(), r.y(), prim.n);
        const Vec3 n = shadingNormal(prim.n, r.x(), r.y(), ng);
        const double scale = std::min(surface.height, patchSize(prim));
        // The hint, just above the floor where the lattice's near march starts inside the cell,
        // is what lets a query use the lattice.
        const int hintPrim = seenThrough < mOptions.exactFloorShadowAbove ? int(&prim - mTracer.prims().data()) : -1;
        return shadeSurface(x, n, ng, -d, surface.material, scale, t, counters, hintPrim, Vec3(r.x(), r.y(), 1e-4));
    }

    // An opaque surface point; its shadow queries start in cell `hintPrim` at `hintR` when that
    // is given (see shadowTransmittance).
    Color shadeSurface(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& view, const Material& m, double scale,
                       double t, Counters& counters, int hintPrim = -1, const Vec3& hintR = Vec3::Zero()) const {
        return detail::shadePhong(mScene.lights, x, n, ng, view, m, Color::Ones(), scale,
                                  [&](const Vec3& origin, const Vec3& l, double distance) {
                                      return shadowTransmittance(origin, l, distance, mConeSpread * t, hintPrim, hintR, counters);
                                  });
    }

    // Transmittance from o toward the light along the unit direction l, up to tMax: opaque
    // faces and cell floors block, texel cells attenuate at the level of the cone `width`
    // (world units, held constant along the shadow ray).
    double shadowTransmittance(const Vec3& o, const Vec3& l, double tMax, double width, int hintPrim,
                               const Vec3& hintR, Counters& counters) const {
        if (const int slot = latticeSlot(l, tMax, hintPrim); slot >= 0)
            return nearAndCachedShadow(slot, hintPrim, hintR, l, width, counters);
        return tracedShadow(o, l, tMax, width, hintPrim, hintR, counters);
    }

    // The slot of the transmittance lattice that answers a shadow query toward l (up to tMax)
    // from inside primitive `prim` (−1: none): a directional light and a point inside a texel
    // cell that has a lattice.
    int latticeSlot(const Vec3& l, double tMax, int prim) const {
        if (mOptions.shadowCacheResolution <= 0 || !std::isinf(tMax) || prim < 0) return -1;
        const int slot = mLightCache.slot(l);  // −1 also when there is no lattice at all
        return slot >= 0 && mLightCache.grid(prim).nw > 0 ? slot : -1;
    }

    // A query at cell coordinates r: the exact transmittance over the first kExactLatticeSteps
    // lattice steps toward the light (marched in the cell's texel at the query's own level: the
    // voxels next to the point, which a lit voxel's own column or leaf makes darker than the
    // lattice nodes around it), times the lattice's value where that march ends. The march stops
    // at the cell's sides, so that the lattice looked up is the right one. Two steps rather than
    // one: on the forest PSNR 49.1 instead of 47.7 dB (sparse bush), 42.4 instead of 41.4 (dense
    // bush, where the lattice blurs the terminator), for no measurable time.
    //
    // `span`, when the query comes from a camera march: the reference-space light direction and
    // the local scale the march took at its span's middle, used instead of the query point's
    // own (the mild-deformation assumption the march itself makes; it saves a Jacobian, its
    // inverse and a cube root per query).
    struct SpanFrame {
        Vec3 light;  ///< unit, tiled reference space
        double scale;  ///< the local scale at the span's middle
    };
    double nearAndCachedShadow(int slot, int primIndex, const Vec3& r, const Vec3& l, double width,
                               Counters& counters, const SpanFrame* span = nullptr) const {
        ++counters.shadow;
        const Prim& prim = mTracer.prims()[std::size_t(primIndex)];
        const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        Vec3 lr;
        if (span) {
            lr = span->light;
        } else {
            Mat3 jt = prim.cell.jacobian(r);
            jt.col(0) /= surface.repeatU;
            jt.col(1) /= surface.repeatV;
            lr = jt.inverse() * l;
            const double len = lr.norm();
            if (!(len > 0) || !std::isfinite(len)) return cachedShadow(slot, primIndex, r, l);
            lr /= len;
        }
        const Vec3 p0 = tile(r, surface);
        double step = kExactLatticeSteps / double(mLightCache.grid(primIndex).nw);
        // Not past the cell's sides: the lattice looked up where the march ends is this cell's.
        const double extent[2] = {surface.repeatU, surface.repeatV};
        for (int a = 0; a < 2; ++a) {
            if (lr[a] > 0) step = std::min(step, std::max(0.0, (extent[a] - p0[a]) / lr[a]));
            else if (lr[a] < 0) step = std::min(step, std::max(0.0, -p0[a] / lr[a]));
        }
        bool floor = false;
        if (p0.z() + step * lr.z() > 1) step = std::max(0.0, (1 - p0.z()) / lr.z());
        if (p0.z() + step * lr.z() < 0) {
            step = std::max(0.0, -p0.z() / lr.z());
            floor = true;  // the step reaches the base surface, which blocks
        }
        const Vec3 p1 = p0 + step * lr;
        const int level = shadowLevel(texel, width / (span ? span->scale : localScale(prim.cell, r, surface)));
        const SegmentTransmittance near = marchTransmittance(*texel.volume, texel.tau, p0, p1, level, kTransmittanceCutoff);
        counters.voxels += near.blocks;
        if (floor || near.transmittance <= kTransmittanceCutoff) return 0;
        const Vec3 rEnd(p1.x() / surface.repeatU, p1.y() / surface.repeatV, p1.z());
        return near.transmittance * cachedShadow(slot, primIndex, rEnd, l);
    }

    // The lattice's value at cell coordinates r of primitive `primIndex`. A node is one exact
    // shadow ray from its point, at the level of the lattice's spacing; node rays are shared by
    // all pixels, so they are not counted in any tile's statistics (which would then depend on
    // which tile came first).
    double cachedShadow(int slot, int primIndex, const Vec3& r, const Vec3& l) const {
        const Prim& prim = mTracer.prims()[std::size_t(primIndex)];
        const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
        const double spacing = 1.0 / double(mLightCache.grid(primIndex).nw);
        return mLightCache.lookup(slot, primIndex, r, [&](const Vec3& node) {
            // Nodes on the cell's faces move in by a hair, so that the ray starts inside.
            const Vec3 rn = node.cwiseMax(Vec3::Constant(1e-4)).cwiseMin(Vec3::Constant(1 - 1e-4));
            Counters uncounted;
            return tracedShadow(prim.cell.map(rn), l, std::numeric_limits<double>::infinity(),
                                localScale(prim.cell, rn, surface) * spacing, primIndex, rn, uncounted);
        });
    }

    detail::LightTransmittanceCache makeLightCache() const {
        const int n = std::min(mOptions.shadowCacheResolution, 256);
        if (n <= 0) return {};
        std::vector<Vec3> directions;
        for (const Light& light : mScene.lights)
            if (light.type == LightType::Directional &&
                std::find(directions.begin(), directions.end(), Vec3(-light.direction)) == directions.end())
                directions.push_back(-light.direction);
        std::vector<detail::LightTransmittanceCache::Grid> grids(mTracer.prims().size());
        // Node blocks are allocated as cells are first queried; the lattice is used only when
        // all of them together would fit in kMaxLatticeNodes (a decision taken here, before any
        // pixel, so that it does not depend on the order of the tiles), otherwise every query
        // casts its ray. Beyond 4 tiles of the texel across a cell, the lattice gets coarser
        // than 8 steps per tile.
        constexpr double kMaxLatticeNodes = double(1 << 26);  // 256 MB of floats
        double total = 0;
        if (!directions.empty())
            for (std::size_t i = 0; i < grids.size(); ++i) {
                const Prim& prim = mTracer.prims()[i];
                if (!prim.textured) continue;
                const SurfaceRuntime& s = mSurfaces[std::size_t(prim.surface)];
                const auto across = [&](double repeat) { return n * int(std::clamp(std::ceil(repeat), 1.0, 4.0)); };
                grids[i] = {across(s.repeatU), across(s.repeatV), n};
                total += double(grids[i].nodes()) * double(directions.size());
            }
        if (total > kMaxLatticeNodes) return {};
        return detail::LightTransmittanceCache(std::move(directions), std::move(grids));
    }

    // The exact path: one ray toward the light.
    double tracedShadow(const Vec3& o, const Vec3& l, double tMax, double width, int hintPrim, const Vec3& hintR,
                        Counters& counters) const {
        ++counters.shadow;
        return detail::walkShadowRay(
            mTracer, mSurfaces, o, l, tMax, hintPrim, hintR, kTransmittanceCutoff,
            [&](const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, bool startsAtHint,
                double transmittance) {
                const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
                const Vec3 p0 = tile(rIn, surface), p1 = tile(rOut, surface);
                const double localWidth = width / localScale(prim.cell, 0.5 * (rIn + rOut), surface);
                // The hybrid's rule for shadows too: the source mesh where the footprint is finer
                // than the volume is faithful, blended over the next level.
                const double meshWeight =
                    texel.meshWeight(chooseLevel(localWidth, mOptions.lodBias, texel.volume->maxLevel()).requested);
                double result = 0;
                if (meshWeight < 1) {
                    const SegmentTransmittance seg = marchTransmittance(*texel.volume, texel.tau, p0, p1,
                                                                        shadowLevel(texel, localWidth),
                                                                        kTransmittanceCutoff / transmittance);
                    counters.voxels += seg.blocks;
                    result = (1 - meshWeight) * seg.transmittance;
                }
                if (meshWeight > 0) {
                    const double length = (p1 - p0).norm();
                    const double sMin = startsAtHint ? (length > 0 ? kSelfIntersectionGap / length : 1.0) : 0.0;
                    if (!texel.source->occluded(p0, p1, sMin)) result += meshWeight;
                }
                return result;
            });
    }

    // A shadow march takes the single level nearest the cone's width (reference units): shadows
    // are not blended.
    int shadowLevel(const TexelRuntime& texel, double width) const {
        const LevelChoice choice = chooseLevel(width, mOptions.lodBias, texel.volume->maxLevel());
        return choice.fineWeight < 0.5 ? choice.coarse : choice.fine;
    }

    static Vec3 tile(const Vec3& r, const SurfaceRuntime& s) { return {r.x() * s.repeatU, r.y() * s.repeatV, r.z()}; }

    static double localScale(const TrilinearCell& cell, const Vec3& r, const SurfaceRuntime& s) {
        return detail::localScale(cell, r, s.repeatU, s.repeatV);
    }

    void marchSpan(const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, double tIn,
                   double tOut, const Vec3& d, PathState& state, Counters& counters) const {
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        const int primIndex = int(&prim - mTracer.prims().data());
        const Vec3 p0 = tile(rIn, surface), p1 = tile(rOut, surface);
        const Vec3 delta = p1 - p0;
        const double length = delta.norm();
        if (!(length > 0) || !std::isfinite(length)) return;
        ++counters.segments;
        const Vec3 dir = delta / length;
        const Vec3 rMid = 0.5 * (rIn + rOut);
        const double scale = localScale(prim.cell, rMid, surface);
        const double tMid = 0.5 * (tIn + tOut);
        const int maxLevel = texel.volume->maxLevel();
        const LevelChoice choice = chooseLevel(mConeSpread * tMid / scale, mOptions.lodBias, maxLevel);
        // A blend weight below mOptions.blendCutoff goes to the other level, which is then the
        // only one marched: the image moves by at most that weight times the difference of the
        // two levels' results (bounded by the test SkippedBlendLevelsMatchTheFullBlend).
        double fineWeight = choice.fineWeight;
        if (fineWeight > 0 && fineWeight < mOptions.blendCutoff) fineWeight = 0;
        if (fineWeight > 1 - mOptions.blendCutoff) fineWeight = 1;
        // The same cut-off for the mesh's share: a share below it is not traced, above 1 − it the
        // volume is not marched.
        double meshWeight = texel.meshWeight(choice.requested);
        if (meshWeight > 0 && meshWeight < mOptions.blendCutoff) meshWeight = 0;
        if (meshWeight > 1 - mOptions.blendCutoff) meshWeight = 1;
        counters.mesh += meshWeight;
        if (meshWeight >= 1) {
            compositeSpan(traceSourceSpan(prim, surface, texel, p0, p1, tIn, tOut, d, counters), choice.level, tMid,
                          state);
            return;
        }
        if (counters.histogram.size() < std::size_t(maxLevel + 1)) counters.histogram.resize(std::size_t(maxLevel + 1), 0.0);
        if (fineWeight < 1) counters.histogram[std::size_t(choice.coarse)] += (1 - fineWeight) * (1 - meshWeight);
        if (fineWeight > 0) counters.histogram[std::size_t(choice.fine)] += fineWeight * (1 - meshWeight);

        // Light directions go to reference space through the inverse Jacobian of the tiled map,
        // taken once per span (the mild-deformation assumption again).
        Mat3 jt = prim.cell.jacobian(rMid);
        jt.col(0) /= surface.repeatU;
        jt.col(1) /= surface.repeatV;
        Mat3 jtInv = jt.inverse();
        if (!jtInv.allFinite()) jtInv = Mat3::Identity();
        const Vec3 view = -dir;
        const Material& m = texel.material;

        const double startT = state.transmittance;
        const std::size_t lights = mScene.lights.size();
        // The shadow rays of the first (coarse) march, by light: where along the span they were
        // taken and what they found. When the second (fine) march of the blend needs a shadow
        // (same rule: first lit voxel, then each time its transmittance has fallen to a
        // quarter), it takes the coarse march's nearest one if that was taken within one coarse
        // voxel of here, instead of casting its own: shadow rays are the costliest part of a
        // march, and the two levels see the same light through the same texel. An
        // approximation (the origin moves by at most a coarse voxel), bounded by the test
        // SharedShadowRaysMatchPerLevelShadowRays.
        const double shareDistance = 1.0 / double(std::int64_t(1) << choice.coarse);
        constexpr int kTrackCapacity = 32;
        struct ShadowTrack {
            int count = 0;
            std::array<double, kTrackCapacity> s, t;
        };
        PerLight<ShadowTrack> tracks(lights);
        // A directional light's direction and irradiance do not depend on the point, nor its
        // reference-space direction within the span: taken once per span.
        struct SpanLight {
            bool directional = false;
            bool usable = false;  ///< directional: lr is finite
            int latticeSlot = -1; ///< directional, usable, and the cell has a transmittance lattice
            Vec3 lw, lr;
            Color e;
            std::optional<ReflectanceKernel> kernel;  ///< directional, usable, fast shading
        };
        PerLight<SpanLight> spanLights(lights);
        bool anyPointLight = false;
        const auto referenceLight = [&](const Vec3& lw, Vec3& lr) {
            lr = jtInv * lw;
            const double len = lr.norm();
            if (!(len > 0) || !std::isfinite(len)) return false;
            lr /= len;
            return true;
        };
        for (std::size_t i = 0; i < lights; ++i) {
            SpanLight& sl = spanLights[i];
            if (mScene.lights[i].type != LightType::Directional) {
                anyPointLight = true;
                continue;
            }
            double distance;
            sl.directional = true;
            lightAt(mScene.lights[i], Vec3::Zero(), sl.lw, distance, sl.e);
            sl.usable = referenceLight(sl.lw, sl.lr);
            if (sl.usable && mOptions.shading == ShadingMode::Fast) sl.kernel.emplace(sl.lr, view, m.shininess);
            if (sl.usable) sl.latticeSlot = latticeSlot(sl.lw, INFINITY, primIndex);
        }
        const double shadowRefresh = std::clamp(mOptions.shadowRefresh, 1e-6, 1.0);
        const double reuseWeight = std::max(mOptions.reflectanceReuseWeight, 0.0);
        const auto run = [&](int level, bool record, double blendWeight) {
            SpanResult r;
            PerLight<octree::ReflectanceFactors> lastReflectance(lights);
            PerLight<char> haveReflectance(lights);
            double reusedShare = 0;
            PerLight<double> shadowT(lights);
            PerLight<double> shadowAt(lights);  // local transmittance when the shadow was taken
            PerLight<char> shadowValid(lights);
            PerLight<int> reuseAt(lights);      // reuse: index of the track's current ray
            counters.voxels += detail::march(*texel.volume, level, p0, dir, length,
                [&](const GridVoxel& voxel, double s, double ds) {
                    const SggxMatrix& sMatrix = voxel.s;
                    const double sigma = texel.tau * double(voxel.density) * detail::normalizedArea(sMatrix, dir);
                    // 1 − exp rather than expm1 (which takes 1.7× as long here): the opacity is
                    // only added to and multiplied with quantities of order one, where its
                    // absolute error (an ulp of 1) is what counts.
                    const double transmit = std::exp(-sigma * ds);
                    const double alpha = 1 - transmit;
                    if (!(alpha > 0)) return true;
                    const double share = startT * r.transmittance * alpha * blendWeight;
                    const bool reuse = share < reuseWeight && reusedShare + share <= 10 * reuseWeight;
                    const double sm = s + 0.5 * ds;
                    // The voxel's cell coordinates: for point lights and shadow queries only.
                    const auto cellPoint = [&] {
                        const Vec3 pt = p0 + sm * dir;
                        return Vec3(pt.x() / surface.repeatU, pt.y() / surface.repeatV, pt.z());
                    };
                    const Color albedo(voxel.albedo[0], voxel.albedo[1], voxel.albedo[2]);
                    Color lk = m.ambient.cwiseProduct(albedo);
                    // The world point: for point lights, and for shadow rays.
                    Vec3 x = Vec3::Zero();
                    bool haveX = false;
                    const auto worldPoint = [&]() -> const Vec3& {
                        if (!haveX) x = prim.cell.map(cellPoint());
                        haveX = true;
                        return x;
                    };
                    if (anyPointLight) worldPoint();
                    for (std::size_t i = 0; i < lights; ++i) {
                        const SpanLight& sl = spanLights[i];
                        Vec3 lw;
                        double distance = std::numeric_limits<double>::infinity();
                        Color e;
                        if (sl.directional) {
                            lw = sl.lw;
                            e = sl.e;
                        } else if (!lightAt(mScene.lights[i], x, lw, distance, e)) {
                            continue;
                        }
                        // One shadow query at the first lit voxel, another each time the local
                        // transmittance has fallen below shadowRefresh of what it was at the
                        // last one: the shadow varies with depth into the texel.
                        if (!shadowValid[i] || r.transmittance < shadowRefresh * shadowAt[i]) {
                            ShadowTrack& track = tracks[i];
                            int nearest = -1;
                            if (!record) {
                                // Samples are in increasing s: resume the scan where it stopped.
                                int& k = reuseAt[i];
                                while (k + 1 < track.count && track.s[std::size_t(k + 1)] <= sm) ++k;
                                for (int c = k; c <= std::min(k + 1, track.count - 1); ++c)
                                    if (std::abs(track.s[std::size_t(c)] - sm) <= shareDistance &&
                                        (nearest < 0 || std::abs(track.s[std::size_t(c)] - sm) <
                                                            std::abs(track.s[std::size_t(nearest)] - sm)))
                                        nearest = c;
                            }
                            if (nearest >= 0) {
                                shadowT[i] = track.t[std::size_t(nearest)];
                            } else {
                                const double width = kShadowConeScale * mConeSpread * (tIn + (tOut - tIn) * (sm / length));
                                const Vec3 rc = cellPoint();
                                if (sl.latticeSlot >= 0) {
                                    const SpanFrame frame{sl.lr, scale};
                                    shadowT[i] = nearAndCachedShadow(sl.latticeSlot, primIndex, rc, lw, width, counters, &frame);
                                } else {
                                    shadowT[i] = shadowTransmittance(worldPoint(), lw, distance, width, primIndex, rc, counters);
                                }
                                if (record && track.count < kTrackCapacity) {
                                    track.s[std::size_t(track.count)] = sm;
                                    track.t[std::size_t(track.count)] = shadowT[i];
                                    ++track.count;
                                }
                            }
                            shadowAt[i] = r.transmittance;
                            shadowValid[i] = true;
                        }
                        if (shadowT[i] <= 0) continue;
                        Vec3 lr = sl.lr;
                        if (sl.directional ? !sl.usable : !referenceLight(lw, lr)) continue;
                        octree::ReflectanceFactors& f = lastReflectance[i];
                        if (reuse && haveReflectance[i]) {
                            reusedShare += share;
                        } else {
                            ++counters.reflectance;
                            f = sl.kernel ? (*sl.kernel)(sMatrix)
                                : mOptions.shading == ShadingMode::Fast
                                    ? reflectanceFast(sMatrix, lr, view, m.shininess)
                                    : reflectanceReference(sMatrix, lr, view, m.shininess, mOptions.referenceSamples);
                            haveReflectance[i] = true;
                        }
                        lk += shadowT[i] * e.cwiseProduct(m.diffuse.cwiseProduct(albedo) * f.diffuse + m.specular * f.specular);
                    }
                    r.radiance += r.transmittance * alpha * lk;
                    r.transmittance *= transmit;
                    return startT * r.transmittance > kTransmittanceCutoff;
                });
            return r;
        };
        SpanResult result;
        if (fineWeight >= 1) {
            result = run(choice.fine, false, 1.0);
        } else {
            result = run(choice.coarse, mOptions.shareShadowRays, 1 - fineWeight);
            if (fineWeight > 0) {
                const SpanResult fine = run(choice.fine, false, fineWeight);
                const double w = fineWeight;
                result.radiance = (1 - w) * result.radiance + w * fine.radiance;
                result.transmittance = (1 - w) * result.transmittance + w * fine.transmittance;
            }
        }
        if (meshWeight > 0) {
            const SpanResult mesh = traceSourceSpan(prim, surface, texel, p0, p1, tIn, tOut, d, counters);
            result.radiance = (1 - meshWeight) * result.radiance + meshWeight * mesh.radiance;
            result.transmittance = (1 - meshWeight) * result.transmittance + meshWeight * mesh.transmittance;
        }
        compositeSpan(result, choice.level, tMid, state);
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
    // to the world by the inverse transpose of the tiled map's Jacobian), its shadows by the
    // hybrid rule of tracedShadow.
    SpanResult traceSourceSpan(const Prim& prim, const SurfaceRuntime& surface, const TexelRuntime& texel, const Vec3& p0,
                               const Vec3& p1, double tIn, double tOut, const Vec3& d, Counters& counters) const {
        const auto hit = texel.source->intersect(p0, p1, 0);
        if (!hit) return {};
        const Vec3 rt = p0 + hit->s * (p1 - p0);
        const Vec3 rc(rt.x() / surface.repeatU, rt.y() / surface.repeatV, rt.z());
        const Vec3 x = prim.cell.map(rc);
        Mat3 jacobian = prim.cell.jacobian(rc);
        jacobian.col(0) /= surface.repeatU;
        jacobian.col(1) /= surface.repeatV;
        Vec3 n = jacobian.inverse().transpose() * hit->normal;
        const double length = n.norm();
        n = length > 0 && std::isfinite(length) ? Vec3(n / length) : Vec3(-d);
        const double scale = localScale(prim.cell, rc, surface);
        const int primIndex = int(&prim - mTracer.prims().data());
        const double t = tIn + hit->s * (tOut - tIn);
        const Color radiance = detail::shadePhong(
            mScene.lights, x, n, n, -d, texel.material, hit->albedo, scale, [&](const Vec3& origin, const Vec3& l, double distance) {
                return tracedShadow(origin, l, distance, mConeSpread * t, primIndex, rc, counters);
            });
        return {radiance, 0.0};
    }

    const Scene& mScene;
    const RenderOptions& mOptions;
    const Tracer& mTracer;
    const std::vector<SurfaceRuntime>& mSurfaces;
    const std::vector<TexelRuntime>& mTexels;
    double mConeSpread;
    detail::LightTransmittanceCache mLightCache = makeLightCache();
};

// The finest level at which the volume lets through what the source mesh does, within
// `tolerance` (absolute transmittance, mean over random chords of the whole texel): from the
// level of least error, finer levels as long as each stays within the tolerance. Finer than
// that, a voxel stands for a piece of one opaque surface that the exponential medium lets
// light through (and shadows itself), and the hybrid traces the mesh instead.
double faithfulLevel(const octree::Octree& tree, const detail::SourceBvh& source, double tau, double tolerance) {
    const auto chords = octree::measureChordTransmittance(
        tree, [&](const Vec3& a, const Vec3& b) { return !source.occluded(a, b, 0); }, tau);
    if (chords.empty()) return std::numeric_limits<double>::infinity();
    std::size_t best = 0;
    for (std::size_t l = 1; l < chords.size(); ++l)
        if (std::abs(chords[l].error()) < std::abs(chords[best].error())) best = l;
    std::size_t level = best;
    while (level + 1 < chords.size() && std::abs(chords[level + 1].error()) <= tolerance) ++level;
    return double(level);
}

}  // namespace

RenderResult renderScene(const Scene& scene, const RenderOptions& options, Progress& progress) {
    const auto loadStart = std::chrono::steady_clock::now();
    RenderResult result;
    const auto [width, height] = detail::imageSize(scene, options.width, options.height);
    const int strata = std::max(1, int(std::ceil(std::sqrt(double(std::max(options.spp, 1))))));

    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    // Texels referenced by some surface (the others are not loaded).
    std::vector<TexelRuntime> texels(scene.texels.size());
    for (const SurfaceDef& s : scene.surfaces) {
        if (!s.texel) continue;
        TexelRuntime& t = texels[*s.texel];
        if (t.volume) continue;
        const TexelDef& def = scene.texels[*s.texel];
        auto tree = def.octree ? def.octree : std::make_shared<const octree::Octree>(octree::readVto(def.volume));
        if (tree->levels.empty() || tree->levels[0].empty())
            throw InputError(def.volume, "octree has no root");
        t.tau = def.tau;
        t.material = def.material;
        if (options.hybrid && (def.sourceData || !def.source.empty())) {
            t.sourceMesh = def.sourceData ? def.sourceData : std::make_shared<const ingest::TriangleMesh>(ingest::loadMesh(def.source));
            t.source = std::make_unique<const detail::SourceBvh>(*t.sourceMesh, tree->info.source);
            t.meshLevel = faithfulLevel(*tree, *t.source, def.tau, options.hybridTolerance);
        }
        t.volume = std::make_unique<const MarchVolume>(std::move(tree));
    }

    const detail::CameraRays camera(scene.camera, width, height);
    const double coneSpread = detail::coneSpread(scene.camera.fovY, height, strata);
    const Integrator integrator(scene, options, *geometry.tracer, geometry.surfaces, texels, coneSpread);
    const auto renderStart = std::chrono::steady_clock::now();
    const double loadSeconds = std::chrono::duration<double>(renderStart - loadStart).count();

    Image image(width, height, options.aovs);
    const int threads = detail::resolveThreads(options.threads);
    std::vector<Counters> tileCounters;
    detail::renderTiles(image, threads, progress, tileCounters, [&](int x, int y, Counters& counters) {
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
    result.stats = detail::summarize(tileCounters, geometry, threads, width, height, strata * strata, wallSeconds, loadSeconds);
    for (const TexelRuntime& t : texels)
        if (t.volume) result.stats.meshLevels.push_back(t.source ? t.meshLevel : -1.0);
    result.image = std::move(image);
    result.warnings = scene.warnings;
    return result;
}

void writeStatsJson(const RenderStats& s, const std::filesystem::path& file) {
    nlohmann::json j;
    j["renderer"] = s.renderer;
    j["wall_seconds"] = s.wallSeconds;
    j["load_seconds"] = s.loadSeconds;
    j["threads"] = s.threads;
    j["width"] = s.width;
    j["height"] = s.height;
    j["spp"] = s.spp;
    j["faces"] = s.faces;
    j["cells"] = s.cells;
    j["rays"] = {{"primary", s.primaryRays}, {"shadow", s.shadowRays}};
    j["cell_segments"] = s.cellSegments;
    j["voxels_visited"] = s.voxelsVisited;
    j["reflectance_evaluations"] = s.reflectanceEvaluations;
    j["level_histogram"] = s.levelHistogram;
    j["mean_level"] = s.meanLevel();
    if (s.renderer == "texel") {
        j["mesh_segments"] = s.meshSegments;
        j["mesh_levels"] = s.meshLevels;
    }
    if (s.renderer != "texel") j["reference_triangles"] = s.referenceTriangles;
    writeFileAtomically(file, j.dump(2) + "\n");
}

}  // namespace vtex::render
