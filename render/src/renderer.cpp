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
#include "per_light.h"
#include "shadow_queries.h"
#include "texel_runtime.h"
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
#include <sstream>

namespace vtex::render {

ApproximationBudget ApproximationBudget::exact() {
    ApproximationBudget b;
    b.shareShadowRays = false;
    b.shadowCacheResolution = 0;
    b.blendCutoff = 0;
    b.reflectanceReuseWeight = 0;
    b.exactFloorShadowAbove = 0;
    b.shadowRefresh = 1;
    return b;
}

bool ApproximationBudget::isExact() const { return *this == exact(); }

std::string ApproximationBudget::key() const {
    std::ostringstream k;
    k.precision(17);
    k << "share_shadow_rays " << shareShadowRays << " shadow_cache_resolution " << shadowCacheResolution << " blend_cutoff "
      << blendCutoff << " reflectance_reuse_weight " << reflectanceReuseWeight << " exact_floor_shadow_above "
      << exactFloorShadowAbove << " shadow_refresh " << shadowRefresh;
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

double patchSize(const Prim& prim) { return detail::patchSize(prim.p); }

using detail::kTransmittanceCutoff;
using detail::localScale;
using detail::PerLight;
using detail::ShadowQueries;
using detail::TexelRuntime;
using detail::tile;

// Shadow rays from inside a texel march one level coarser than the camera ray (a cone twice as
// wide): soft shadows need less detail than what is seen, and this halves their cost.
constexpr double kShadowConeScale = 2.0;

struct SpanResult {
    Color radiance = Color::Zero();
    double transmittance = 1;
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
        const int hintPrim = seenThrough < mOptions.approximations.exactFloorShadowAbove ? int(&prim - mTracer.prims().data()) : -1;
        return shadeSurface(x, n, ng, -d, surface.material, scale, t, counters, hintPrim, Vec3(r.x(), r.y(), 1e-4));
    }

    // An opaque surface point; its shadow queries start in cell `hintPrim` at `hintR` when that
    // is given (see shadowTransmittance).
    Color shadeSurface(const Vec3& x, const Vec3& n, const Vec3& ng, const Vec3& view, const Material& m, double scale,
                       double t, Counters& counters, int hintPrim = -1, const Vec3& hintR = Vec3::Zero()) const {
        return detail::shadePhong(mScene.lights, x, n, ng, view, m, Color::Ones(), scale,
                                  [&](const Vec3& origin, const Vec3& l, double distance) {
                                      return mShadows.shadowTransmittance(origin, l, distance, mConeSpread * t, hintPrim, hintR, counters);
                                  });
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
        // A blend weight below mOptions.approximations.blendCutoff goes to the other level, which is then the
        // only one marched: the image moves by at most that weight times the difference of the
        // two levels' results (bounded by the test SkippedBlendLevelsMatchTheFullBlend).
        double fineWeight = choice.fineWeight;
        if (fineWeight > 0 && fineWeight < mOptions.approximations.blendCutoff) fineWeight = 0;
        if (fineWeight > 1 - mOptions.approximations.blendCutoff) fineWeight = 1;
        // The same cut-off for the mesh's share: a share below it is not traced, above 1 − it the
        // volume is not marched.
        double meshWeight = texel.meshWeight(choice.requested);
        if (meshWeight > 0 && meshWeight < mOptions.approximations.blendCutoff) meshWeight = 0;
        if (meshWeight > 1 - mOptions.approximations.blendCutoff) meshWeight = 1;
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
            Vec3 lw = Vec3::Zero(), lr = Vec3::Zero();
            Color e = Color::Zero();
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
            if (sl.usable) sl.latticeSlot = mShadows.latticeSlot(sl.lw, INFINITY, primIndex);
        }
        const double shadowRefresh = std::clamp(mOptions.approximations.shadowRefresh, 1e-6, 1.0);
        const double reuseWeight = std::max(mOptions.approximations.reflectanceReuseWeight, 0.0);
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
                                    const ShadowQueries::SpanFrame frame{sl.lr, scale};
                                    shadowT[i] = mShadows.nearAndCachedShadow(sl.latticeSlot, primIndex, rc, lw, width, counters, &frame);
                                } else {
                                    shadowT[i] = mShadows.shadowTransmittance(worldPoint(), lw, distance, width, primIndex, rc, counters);
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
            result = run(choice.coarse, mOptions.approximations.shareShadowRays, 1 - fineWeight);
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
                return mShadows.tracedShadow(origin, l, distance, mConeSpread * t, primIndex, rc, counters);
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
};

}  // namespace

RenderResult renderScene(const Scene& scene, const RenderOptions& options, Progress& progress) {
    const auto loadStart = std::chrono::steady_clock::now();
    RenderResult result;
    const auto [width, height] = detail::imageSize(scene, options.width, options.height);
    const int strata = std::max(1, int(std::ceil(std::sqrt(double(std::max(options.spp, 1))))));

    const detail::SceneGeometry geometry = detail::buildSceneGeometry(scene);
    // Texels referenced by some surface (the others are not loaded).
    const std::vector<TexelRuntime> texels = detail::loadTexels(scene, options);

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
    result.stats.approximations = options.approximations.isExact() ? "exact" : options.approximations.key();
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
        j["approximations"] = s.approximations;
    }
    if (s.renderer != "texel") j["reference_triangles"] = s.referenceTriangles;
    writeFileAtomically(file, j.dump(2) + "\n");
}

}  // namespace vtex::render
