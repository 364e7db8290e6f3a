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
#include "light_cache.h"
#include "march.h"
#include "tracer.h"

#include <Eigen/Dense>
#include <nlohmann/json.hpp>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <numbers>

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

using detail::Hit;
using detail::Prim;
using detail::Tracer;

constexpr double kTransmittanceCutoff = 1e-4;
// Shadow rays from inside a texel march one level coarser than the camera ray (a cone twice as
// wide): soft shadows need less detail than what is seen, and this halves their cost.
constexpr double kShadowConeScale = 2.0;
// Lattice steps marched exactly from a shadow query before the lattice is looked up.
constexpr double kExactLatticeSteps = 2.0;

struct TexelRuntime {
    std::shared_ptr<const octree::Octree> tree;
    int maxLevel = 0;
    double tau = 1;
    Material material;
};

struct SurfaceRuntime {
    Material material;
    int texel = -1;
    double repeatU = 1, repeatV = 1;
    double height = 0;
};

struct Counters {
    std::uint64_t primary = 0, shadow = 0, segments = 0, voxels = 0, reflectance = 0;
    std::vector<double> histogram;
    void add(const Counters& o) {
        primary += o.primary;
        shadow += o.shadow;
        segments += o.segments;
        voxels += o.voxels;
        reflectance += o.reflectance;
        if (histogram.size() < o.histogram.size()) histogram.resize(o.histogram.size(), 0.0);
        for (std::size_t i = 0; i < o.histogram.size(); ++i) histogram[i] += o.histogram[i];
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

// An offset along the normal that lifts a surface point clear of the rounding of its own
// intersection (pbrt-v4's OffsetRayOrigin idea, with a bound relative to the coordinates and
// to the local feature size rather than a propagated error).
double offsetDistance(const Vec3& x, double scale) { return 1e-9 * x.cwiseAbs().maxCoeff() + 1e-6 * scale; }

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
                opaque(state, hit->t, shadeFloor(prim, surface, span.rIn, d, hit->t, counters));
                break;
            }
            const auto rIn = entryCoords(prim, *hit, o, d, -1, Vec3::Zero());
            if (rIn) marchSpan(prim, surface, *rIn, span.rOut, hit->t, span.tOut, state, counters);
            if (state.transmittance <= kTransmittanceCutoff) break;
            if (span.faceOut == 0) {
                opaque(state, span.tOut, shadeFloor(prim, surface, span.rOut, d, span.tOut, counters));
                break;
            }
            tNear = span.tOut;
        }
        return state;
    }

private:
    static Vec3 bilerp(const std::array<Vec3, 4>& p, double u, double v) {
        const Vec3 a = p[0] + u * (p[1] - p[0]);
        const Vec3 b = p[2] + u * (p[3] - p[2]);
        return a + v * (b - a);
    }
    static Vec3 geometricNormal(const std::array<Vec3, 4>& p, double u, double v, const std::array<Vec3, 4>& n) {
        const Vec3 du = (1 - v) * (p[1] - p[0]) + v * (p[3] - p[2]);
        const Vec3 dv = (1 - u) * (p[2] - p[0]) + u * (p[3] - p[1]);
        Vec3 ng = du.cross(dv);
        // At a triangle's collapsed corner the cross product vanishes: use the other corners'.
        if (!(ng.squaredNorm() > 0) || !ng.allFinite()) ng = (p[1] - p[0]).cross(p[3] - p[0]);
        if (!(ng.squaredNorm() > 0) || !ng.allFinite()) ng = bilerp(n, u, v);
        const double len = ng.norm();
        return len > 0 && std::isfinite(len) ? Vec3(ng / len) : Vec3(0, 0, 1);
    }
    static Vec3 shadingNormal(const std::array<Vec3, 4>& n, double u, double v, const Vec3& ng) {
        Vec3 s = bilerp(n, u, v);
        const double len = s.norm();
        if (!(len > 0) || !std::isfinite(len)) return ng;
        s /= len;
        return s.dot(ng) < 0 ? Vec3(-s) : s;
    }
    static double patchSize(const Prim& prim) {
        double size = 0;
        for (int i = 0; i < 4; ++i)
            for (int j = i + 1; j < 4; ++j) size = std::max(size, (prim.p[i] - prim.p[j]).norm());
        return size;
    }

    static void opaque(PathState& state, double t, const Color& radiance) {
        state.radiance += state.transmittance * radiance;
        state.noteOpacity(t, state.transmittance, 0);
        state.transmittance = 0;
    }

    // The cell coordinates where the ray enters at hit.t: the face parameters when it crossed a
    // face there, the caller's hint when it starts inside the hinted cell, otherwise the inverse
    // trilinear map of the world point.
    std::optional<Vec3> entryCoords(const Prim& prim, const Hit& hit, const Vec3& o, const Vec3& d, int hintPrim,
                                    const Vec3& hintR) const {
        const CellSpan& span = hit.span;
        const double tolerance = 1e-9 * std::max(1.0, std::abs(span.tOut)) + 1e-12 * prim.cell.size();
        if (span.faceIn >= 0 && hit.t - span.tIn <= tolerance) return span.rIn;
        if (span.faceIn < 0 && hit.prim == hintPrim) return hintR;
        const Vec3 guess = span.faceIn >= 0
                               ? Vec3(span.rIn + (span.rOut - span.rIn) * std::clamp((hit.t - span.tIn) / (span.tOut - span.tIn), 0.0, 1.0))
                               : Vec3(0.5, 0.5, 0.5);
        return prim.cell.inverse(o + hit.t * d, guess, 1e-7, 1e-3);
    }

    Color shadeFloor(const Prim& prim, const SurfaceRuntime& surface, const Vec3& r, const Vec3& d, double t,
                     Counters& counters) const {
        const Vec3 x = prim.cell.map(Vec3(r.x(), r.y(), 0));
        const auto bottom = prim.cell.faceCorners(0);
        const Vec3 ng = geometricNormal(bottom, r.x(), r.y(), prim.n);
        const Vec3 n = shadingNormal(prim.n, r.x(), r.y(), ng);
        return shadeSurface(x, n, ng, -d, surface.material, std::min(surface.height, patchSize(prim)), t, counters);
    }

    // Phong (DESIGN.md, "Radiometry"), two-sided: the normals are turned toward the viewer.
    Color shadeSurface(const Vec3& x, Vec3 n, Vec3 ng, const Vec3& view, const Material& m, double scale, double t,
                       Counters& counters) const {
        if (ng.dot(view) < 0) {
            ng = -ng;
            n = -n;
        }
        if (n.dot(view) < 0) n = ng;  // a shading normal past the silhouette
        Color out = m.ambient;
        const Vec3 origin = x + offsetDistance(x, scale) * ng;
        for (const Light& light : mScene.lights) {
            Vec3 l;
            double distance;
            Color e;
            if (!lightAt(light, x, l, distance, e)) continue;
            const double cosTheta = n.dot(l);
            if (cosTheta <= 0 || ng.dot(l) <= 0) continue;
            const double shadow = shadowTransmittance(origin, l, distance, mConeSpread * t, -1, Vec3::Zero(), counters);
            if (shadow <= 0) continue;
            const Vec3 mirror = 2 * n.dot(l) * n - l;
            const double cosAlpha = std::max(0.0, mirror.dot(view));
            const Color f = m.diffuse / std::numbers::pi +
                            m.specular * ((m.shininess + 2) / (2 * std::numbers::pi) * std::pow(cosAlpha, m.shininess));
            out += shadow * cosTheta * e.cwiseProduct(f);
        }
        return out;
    }

    // Direction toward the light, distance to it (∞ for directional) and irradiance at x.
    static bool lightAt(const Light& light, const Vec3& x, Vec3& l, double& distance, Color& e) {
        if (light.type == LightType::Directional) {
            l = -light.direction;
            distance = std::numeric_limits<double>::infinity();
            e = light.color;
            return true;
        }
        const Vec3 delta = light.position - x;
        distance = delta.norm();
        if (!(distance > 0) || !std::isfinite(distance)) return false;
        l = delta / distance;
        e = light.color / (distance * distance);
        return e.allFinite();
    }

    // Transmittance from o toward the light along the unit direction l, up to tMax: opaque
    // faces and cell floors block, texel cells attenuate at the level of the cone `width`
    // (world units, held constant along the shadow ray).
    double shadowTransmittance(const Vec3& o, const Vec3& l, double tMax, double width, int hintPrim,
                               const Vec3& hintR, Counters& counters) const {
        // A directional light and a point inside a texel cell: the cell's transmittance lattice.
        if (mOptions.shadowCacheResolution > 0 && std::isinf(tMax)) {
            const int slot = mLightCache.slot(l);
            if (slot >= 0) {
                if (hintPrim >= 0 && mLightCache.grid(hintPrim).nw > 0) {
                    ++counters.shadow;
                    return nearAndCachedShadow(slot, hintPrim, hintR, l, width, counters);
                }
            }
        }
        return tracedShadow(o, l, tMax, width, hintPrim, hintR, counters);
    }

    // A query at cell coordinates r: the exact transmittance over the first kExactLatticeSteps
    // lattice steps toward the light (marched in the cell's texel at the query's own level: the
    // voxels next to the point, which a lit voxel's own column or leaf makes darker than the
    // lattice nodes around it), times the lattice's value where that march ends. The march stops
    // at the cell's sides, so that the lattice looked up is the right one. Two steps rather than
    // one: on the forest PSNR 49.1 instead of 47.7 dB (sparse bush), 42.4 instead of 41.4 (dense
    // bush, where the lattice blurs the terminator), for no measurable time.
    double nearAndCachedShadow(int slot, int primIndex, const Vec3& r, const Vec3& l, double width,
                               Counters& counters) const {
        const Prim& prim = mTracer.prims()[std::size_t(primIndex)];
        const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        Mat3 jt = prim.cell.jacobian(r);
        jt.col(0) /= surface.repeatU;
        jt.col(1) /= surface.repeatV;
        Vec3 lr = jt.inverse() * l;
        const double len = lr.norm();
        if (!(len > 0) || !std::isfinite(len)) return cachedShadow(slot, primIndex, r, l);
        lr /= len;
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
        const double scale = localScale(prim.cell, r, surface);
        const LevelChoice choice = chooseLevel(width / scale, mOptions.lodBias, texel.maxLevel);
        const int level = choice.fineWeight < 0.5 ? choice.coarse : choice.fine;
        const SegmentTransmittance near = marchTransmittance(*texel.tree, texel.tau, p0, p1, level, kTransmittanceCutoff,
                                                             &mEmptySpace[std::size_t(surface.texel)]);
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
        double transmittance = 1;
        double tNear = 0;
        detail::SpanCache cache;
        for (int step = 0; step < 4096; ++step) {
            const auto hit = mTracer.trace(o, l, tNear, tMax, &cache);
            if (!hit) break;
            const Prim& prim = mTracer.prims()[std::size_t(hit->prim)];
            if (!prim.textured) return 0;
            const CellSpan& span = hit->span;
            if (span.faceIn == 0 && hit->t <= span.tIn) return 0;
            const SurfaceRuntime& surface = mSurfaces[std::size_t(prim.surface)];
            const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
            const auto rIn = entryCoords(prim, *hit, o, l, hintPrim, hintR);
            const double tOut = std::min(span.tOut, tMax);
            if (rIn) {
                const Vec3 rOut = tOut < span.tOut ? prim.cell.inverse(o + tOut * l, span.rOut).value_or(span.rOut)
                                                   : span.rOut;
                const Vec3 p0 = tile(*rIn, surface), p1 = tile(rOut, surface);
                const Vec3 rMid = 0.5 * (*rIn + rOut);
                const double scale = localScale(prim.cell, rMid, surface);
                const LevelChoice choice = chooseLevel(width / scale, mOptions.lodBias, texel.maxLevel);
                const int level = choice.fineWeight < 0.5 ? choice.coarse : choice.fine;
                const SegmentTransmittance seg = marchTransmittance(*texel.tree, texel.tau, p0, p1, level,
                                                                    kTransmittanceCutoff / transmittance,
                                                                    &mEmptySpace[std::size_t(surface.texel)]);
                counters.voxels += seg.blocks;
                transmittance *= seg.transmittance;
                if (transmittance <= kTransmittanceCutoff) return 0;
            }
            if (tOut < span.tOut) break;
            if (span.faceOut == 0) return 0;  // leaves through the base surface
            tNear = span.tOut;
        }
        return transmittance;
    }

    static Vec3 tile(const Vec3& r, const SurfaceRuntime& s) { return {r.x() * s.repeatU, r.y() * s.repeatV, r.z()}; }

    static double localScale(const TrilinearCell& cell, const Vec3& r, const SurfaceRuntime& s) {
        return detail::localScale(cell, r, s.repeatU, s.repeatV);
    }

    void marchSpan(const Prim& prim, const SurfaceRuntime& surface, const Vec3& rIn, const Vec3& rOut, double tIn,
                   double tOut, PathState& state, Counters& counters) const {
        const TexelRuntime& texel = mTexels[std::size_t(surface.texel)];
        const Vec3 p0 = tile(rIn, surface), p1 = tile(rOut, surface);
        const Vec3 delta = p1 - p0;
        const double length = delta.norm();
        if (!(length > 0) || !std::isfinite(length)) return;
        ++counters.segments;
        const Vec3 dir = delta / length;
        const Vec3 rMid = 0.5 * (rIn + rOut);
        const double scale = localScale(prim.cell, rMid, surface);
        const double tMid = 0.5 * (tIn + tOut);
        const LevelChoice choice = chooseLevel(mConeSpread * tMid / scale, mOptions.lodBias, texel.maxLevel);
        // A blend weight below mOptions.blendCutoff goes to the other level, which is then the
        // only one marched: the image moves by at most that weight times the difference of the
        // two levels' results (bounded by the test SkippedBlendLevelsMatchTheFullBlend).
        double fineWeight = choice.fineWeight;
        if (fineWeight > 0 && fineWeight < mOptions.blendCutoff) fineWeight = 0;
        if (fineWeight > 1 - mOptions.blendCutoff) fineWeight = 1;
        if (counters.histogram.size() < std::size_t(texel.maxLevel + 1)) counters.histogram.resize(std::size_t(texel.maxLevel + 1), 0.0);
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
            Vec3 lw, lr;
            Color e;
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
        }
        const auto run = [&](int level, bool record) {
            Result r;
            std::array<double, 16> shadowT{};
            std::array<double, 16> shadowAt{};  // local transmittance when the shadow was taken
            std::array<bool, 16> shadowValid{};
            std::array<int, 16> reuseAt{};      // reuse: index of the track's current ray
            counters.voxels += detail::marchBlocks(*texel.tree, level, p0, dir, length,
                [&](const octree::OctreeNode& node, double s, double ds) {
                    const auto& data = node.data;
                    const SggxMatrix sMatrix = voxelS(data);
                    const double sigma = texel.tau * double(data.density) * detail::normalizedArea(sMatrix, dir);
                    const double alpha = -std::expm1(-sigma * ds);
                    if (!(alpha > 0)) return true;
                    const double sm = s + 0.5 * ds;
                    const Vec3 pt = p0 + sm * dir;
                    const Vec3 rc(pt.x() / surface.repeatU, pt.y() / surface.repeatV, pt.z());
                    const double tWorld = tIn + (tOut - tIn) * (sm / length);
                    const Color albedo(data.albedo[0], data.albedo[1], data.albedo[2]);
                    Color lk = m.ambient.cwiseProduct(albedo);
                    // The world point: for point lights, and for shadow rays.
                    Vec3 x = Vec3::Zero();
                    bool haveX = false;
                    const auto worldPoint = [&]() -> const Vec3& {
                        if (!haveX) x = prim.cell.map(rc);
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
                        // One shadow ray at the first lit voxel, another each time the local
                        // transmittance has fallen to a quarter since: the shadow varies with
                        // depth into the texel, not from voxel to voxel.
                        if (!shadowValid[i] || r.transmittance < 0.25 * shadowAt[i]) {
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
                                shadowT[i] = shadowTransmittance(worldPoint(), lw, distance, kShadowConeScale * mConeSpread * tWorld,
                                                                 int(&prim - mTracer.prims().data()), rc, counters);
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
                        ++counters.reflectance;
                        const auto f = mOptions.shading == ShadingMode::Fast
                                           ? reflectanceFast(sMatrix, lr, view, m.shininess)
                                           : reflectanceReference(sMatrix, lr, view, m.shininess, mOptions.referenceSamples);
                        lk += shadowT[i] * e.cwiseProduct(m.diffuse.cwiseProduct(albedo) * f.diffuse + m.specular * f.specular);
                    }
                    r.radiance += r.transmittance * alpha * lk;
                    r.transmittance *= 1 - alpha;
                    return startT * r.transmittance > kTransmittanceCutoff;
                }, mEmptySpace[std::size_t(surface.texel)].level(level));
            return r;
        };
        Result result;
        if (fineWeight >= 1) {
            result = run(choice.fine, false);
        } else {
            result = run(choice.coarse, mOptions.shareShadowRays);
            if (fineWeight > 0) {
                const Result fine = run(choice.fine, false);
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
    std::vector<EmptySpace> mEmptySpace = makeEmptySpace();

    // Empty-space distances of each texel's octree (texel_march.h), for the marches to leap over
    // runs of empty voxels; same images, fewer empty steps.
    std::vector<EmptySpace> makeEmptySpace() const {
        std::vector<EmptySpace> out(mTexels.size());
        for (std::size_t i = 0; i < mTexels.size(); ++i)
            if (mTexels[i].tree) out[i] = emptySpace(*mTexels[i].tree);
        return out;
    }
};

}  // namespace

RenderResult renderScene(const Scene& scene, const RenderOptions& options, Progress& progress) {
    const auto loadStart = std::chrono::steady_clock::now();
    RenderResult result;
    const int width = options.width > 0 ? options.width : scene.camera.width;
    const int height = options.height > 0 ? options.height : scene.camera.height;
    if (width <= 0 || height <= 0 || width > 16384 || height > 16384)
        throw InputError(scene.file, "image size must be in [1, 16384]");
    const int strata = std::max(1, int(std::ceil(std::sqrt(double(std::max(options.spp, 1))))));

    // Texels referenced by some surface (the others are not loaded).
    std::vector<TexelRuntime> texels(scene.texels.size());
    for (const SurfaceDef& s : scene.surfaces) {
        if (!s.texel) continue;
        if (*s.texel >= scene.texels.size()) throw InputError(scene.file, "texel index out of range", "surface.texel");
        TexelRuntime& t = texels[*s.texel];
        if (t.tree) continue;
        const TexelDef& def = scene.texels[*s.texel];
        t.tree = def.octree ? def.octree : std::make_shared<const octree::Octree>(octree::readVto(def.volume));
        if (t.tree->levels.empty() || t.tree->levels[0].empty())
            throw InputError(def.volume, "octree has no root");
        t.maxLevel = int(t.tree->levels.size()) - 1;
        t.tau = def.tau;
        t.material = def.material;
    }

    // Faces: plain patches, or cells over them.
    std::vector<SurfaceRuntime> surfaces;
    std::vector<Prim> prims;
    std::uint64_t cells = 0;
    for (std::size_t si = 0; si < scene.surfaces.size(); ++si) {
        const SurfaceDef& def = scene.surfaces[si];
        SurfaceRuntime s;
        s.material = def.material;
        s.texel = def.texel ? int(*def.texel) : -1;
        s.repeatU = def.repeat[0];
        s.repeatV = def.repeat[1];
        s.height = def.height;
        surfaces.push_back(s);
        const auto mesh = def.meshData ? def.meshData : std::make_shared<const ingest::QuadMesh>(ingest::loadBaseMesh(def.mesh));
        for (std::size_t f = 0; f < mesh->quads.size(); ++f) {
            Prim prim;
            prim.surface = int(si);
            prim.face = int(f);
            if (!detail::baseFaceCorners(*mesh, f, prim.p, prim.n))
                throw InputError(def.mesh, "face " + std::to_string(f) + " has an invalid corner");
            if (def.texel) {
                prim.textured = true;
                prim.cell = TrilinearCell(prim.p, prim.n, def.height, def.placement == Placement::Under);
                ++cells;
            }
            prims.push_back(prim);
        }
    }
    const std::uint64_t faceCount = prims.size();
    const Tracer tracer(std::move(prims));

    // Camera.
    const Camera& cam = scene.camera;
    const Vec3 forward = (cam.lookAt - cam.position).normalized();
    const Vec3 right = forward.cross(cam.up).normalized();
    const Vec3 up = right.cross(forward);
    const double tanHalf = std::tan(cam.fovY * std::numbers::pi / 360);
    const double aspect = double(width) / double(height);
    const double coneSpread = detail::coneSpread(cam.fovY, height, strata);

    Integrator integrator(scene, options, tracer, surfaces, texels, coneSpread);
    const auto renderStart = std::chrono::steady_clock::now();
    result.stats.loadSeconds = std::chrono::duration<double>(renderStart - loadStart).count();

    Image image(width, height, options.aovs);
    constexpr int kTile = 16;
    const int tilesX = (width + kTile - 1) / kTile, tilesY = (height + kTile - 1) / kTile;
    const int tiles = tilesX * tilesY;
    std::vector<Counters> tileCounters;
    tileCounters.resize(std::size_t(tiles));
    const int threads = options.threads > 0 ? options.threads : tbb::this_task_arena::max_concurrency();
    progress.start("render", std::uint64_t(tiles));
    tbb::task_arena arena(threads);
    arena.execute([&] {
        tbb::parallel_for(tbb::blocked_range<int>(0, tiles, 1), [&](const tbb::blocked_range<int>& range) {
            for (int tileIndex = range.begin(); tileIndex != range.end(); ++tileIndex) {
                if (progress.wasInterrupted()) return;
                Counters& counters = tileCounters[std::size_t(tileIndex)];
                const int x0 = (tileIndex % tilesX) * kTile, y0 = (tileIndex / tilesX) * kTile;
                for (int y = y0; y < std::min(y0 + kTile, height); ++y) {
                    for (int x = x0; x < std::min(x0 + kTile, width); ++x) {
                        Color sum = Color::Zero();
                        double alpha = 0, depth = 0, levelSum = 0, levelWeight = 0;
                        int depthCount = 0;
                        for (int sy = 0; sy < strata; ++sy) {
                            for (int sx = 0; sx < strata; ++sx) {
                                const double px = (x + (sx + 0.5) / strata) / width;
                                const double py = (y + (sy + 0.5) / strata) / height;
                                const Vec3 d = (forward + (2 * px - 1) * tanHalf * aspect * right +
                                                (1 - 2 * py) * tanHalf * up).normalized();
                                const PathState s = integrator.radiance(cam.position, d, counters);
                                sum += s.radiance;
                                alpha += 1 - s.transmittance;
                                if (s.depthSet) {
                                    depth += s.depth;
                                    ++depthCount;
                                }
                                levelSum += s.levelSum;
                                levelWeight += s.levelWeight;
                            }
                        }
                        const double n = double(strata * strata);
                        const std::size_t i = std::size_t(y) * std::size_t(width) + std::size_t(x);
                        for (int c = 0; c < 3; ++c) image.rgba[4 * i + std::size_t(c)] = float(sum[c] / n);
                        image.rgba[4 * i + 3] = float(alpha / n);
                        if (options.aovs) {
                            image.depth[i] = depthCount ? float(depth / depthCount) : 0.0f;
                            image.level[i] = levelWeight > 0 ? float(levelSum / levelWeight) : -1.0f;
                        }
                    }
                }
                progress.advance(1);
            }
        });
    });
    progress.finish();

    Counters total;
    for (const Counters& c : tileCounters) total.add(c);
    RenderStats& st = result.stats;
    st.wallSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - renderStart).count();
    st.threads = threads;
    st.width = width;
    st.height = height;
    st.spp = strata * strata;
    st.faces = faceCount;
    st.cells = cells;
    st.primaryRays = total.primary;
    st.shadowRays = total.shadow;
    st.cellSegments = total.segments;
    st.voxelsVisited = total.voxels;
    st.reflectanceEvaluations = total.reflectance;
    st.levelHistogram = total.histogram;
    result.image = std::move(image);
    result.warnings = scene.warnings;
    return result;
}

void writeStatsJson(const RenderStats& s, const std::filesystem::path& file) {
    nlohmann::json j;
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
    writeFileAtomically(file, j.dump(2) + "\n");
}

}  // namespace vtex::render
