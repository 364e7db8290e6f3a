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

#include "footprint.h"
#include "frame.h"
#include "light_cache.h"
#include "march.h"
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

struct TexelRuntime {
    std::unique_ptr<const MarchVolume> volume;
    double tau = 1;
    Material material;
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
            if (rIn) marchSpan(prim, surface, *rIn, span.rOut, hit->t, span.tOut, state, counters);
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
            [&](const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, bool,
                double transmittance) {
                const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
                const Vec3 p0 = tile(rIn, surface), p1 = tile(rOut, surface);
                const int level = shadowLevel(texel, width / localScale(prim.cell, 0.5 * (rIn + rOut), surface));
                const SegmentTransmittance seg = marchTransmittance(*texel.volume, texel.tau, p0, p1, level,
                                                                    kTransmittanceCutoff / transmittance);
                counters.voxels += seg.blocks;
                return seg.transmittance;
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
                   double tOut, PathState& state, Counters& counters) const {
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
        if (counters.histogram.size() < std::size_t(maxLevel + 1)) counters.histogram.resize(std::size_t(maxLevel + 1), 0.0);
        if (fineWeight < 1) counters.histogram[std::size_t(choice.coarse)] += 1 - fineWeight;
        if (fineWeight > 0) counters.histogram[std::size_t(choice.fine)] += fineWeight;

        // Light directions go to reference space through the inverse Jacobian of the tiled map,
        // taken once per span (the mild-deformation assumption again).
        Mat3 jt = prim.cell.jacobian(rMid);
        jt.col(0) /= surface.repeatU;
        jt.col(1) /= surface.repeatV;
        Mat3 jtInv = jt.inverse();
        if (!jtInv.allFinite()) jtInv = Mat3::Identity();
        const Vec3 view = -dir;
        const Material& m = texel.material;

        struct Result {
            Color radiance = Color::Zero();
            double transmittance = 1;
        };
        const double startT = state.transmittance;
        const std::size_t lights = std::min<std::size_t>(mScene.lights.size(), 16);
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
        std::array<ShadowTrack, 16> tracks;
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
        std::array<SpanLight, 16> spanLights;
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
            Result r;
            std::array<octree::ReflectanceFactors, 16> lastReflectance;
            std::array<bool, 16> haveReflectance{};
            double reusedShare = 0;
            std::array<double, 16> shadowT{};
            std::array<double, 16> shadowAt{};  // local transmittance when the shadow was taken
            std::array<bool, 16> shadowValid{};
            std::array<int, 16> reuseAt{};      // reuse: index of the track's current ray
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
                                const Vec3 rc = cellPoint();
                                const double width = kShadowConeScale * mConeSpread * (tIn + (tOut - tIn) * (sm / length));
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
        Result result;
        if (fineWeight >= 1) {
            result = run(choice.fine, false, 1.0);
        } else {
            result = run(choice.coarse, mOptions.shareShadowRays, 1 - fineWeight);
            if (fineWeight > 0) {
                const Result fine = run(choice.fine, false, fineWeight);
                const double w = fineWeight;
                result.radiance = (1 - w) * result.radiance + w * fine.radiance;
                result.transmittance = (1 - w) * result.transmittance + w * fine.transmittance;
            }
        }
        const double before = state.transmittance;
        state.radiance += before * result.radiance;
        state.transmittance = before * result.transmittance;
        const double absorbed = before - state.transmittance;
        state.levelSum += absorbed * choice.level;
        state.levelWeight += absorbed;
        state.noteOpacity(tMid, before, state.transmittance);
    }

    const Scene& mScene;
    const RenderOptions& mOptions;
    const Tracer& mTracer;
    const std::vector<SurfaceRuntime>& mSurfaces;
    const std::vector<TexelRuntime>& mTexels;
    double mConeSpread;
    detail::LightTransmittanceCache mLightCache = makeLightCache();
};

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
        t.volume = std::make_unique<const MarchVolume>(std::move(tree));
        t.tau = def.tau;
        t.material = def.material;
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
    if (s.renderer != "texel") j["reference_triangles"] = s.referenceTriangles;
    writeFileAtomically(file, j.dump(2) + "\n");
}

}  // namespace vtex::render
