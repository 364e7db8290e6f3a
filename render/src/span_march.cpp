// See span_march.h.
#include "span_march.h"

#include <vtex/render/texel_march.h>

#include "march.h"

#include <Eigen/Dense>

#include <algorithm>
#include <cmath>
#include <limits>

namespace vtex::render::detail {
namespace {

// Shadow rays from inside a texel march one level coarser than the camera ray (a cone twice as
// wide): soft shadows need less detail than what is seen, and this halves their cost.
constexpr double kShadowConeScale = 2.0;

// A material without specular colour needs no specular factor: the fast kernel then skips the
// Phong lobe's points (reflectance_kernel.h).
bool hasSpecular(const Material& m) { return (m.specular.array() != 0).any(); }

// What one march keeps per light as it goes: the last shadow query and the last reflectance.
struct MarchLight {
    primitive::ReflectanceFactors reflectance;
    bool haveReflectance = false;
    double shadow = 0;
    double shadowAt = 0;  ///< the march's transmittance when the shadow was taken
    bool shadowValid = false;
    int reuseAt = 0;      ///< reuse: index of the track's current query
};

// The recorded query nearest to sm within shareDistance, −1 if none; `k` resumes the scan
// (queries are recorded, and looked up, in increasing s).
int nearestRecorded(const SpanContext::ShadowTrack& track, double sm, double shareDistance, int& k) {
    while (k + 1 < track.count && track.s[std::size_t(k + 1)] <= sm) ++k;
    int nearest = -1;
    for (int c = k; c <= std::min(k + 1, track.count - 1); ++c)
        if (std::abs(track.s[std::size_t(c)] - sm) <= shareDistance &&
            (nearest < 0 || std::abs(track.s[std::size_t(c)] - sm) < std::abs(track.s[std::size_t(nearest)] - sm)))
            nearest = c;
    return nearest;
}

}  // namespace

SpanContext::SpanContext(const Scene& scene, const RenderOptions& options, const ShadowQueries& shadows, const Prim& prim_,
                         const SurfaceRuntime& surface_, const TexelRuntime& texel_, const Vec3& rIn,
                         const Vec3& rOut, double tIn_, double tOut_, double scale_, double startTransmittance,
                         int coarseLevel)
    : prim(prim_), surface(surface_), texel(texel_), tIn(tIn_), tOut(tOut_), scale(scale_),
      startT(startTransmittance), shareDistance(1.0 / double(std::int64_t(1) << coarseLevel)),
      lights(scene.lights.size()), tracks(scene.lights.size()) {
    p0 = tile(rIn, prim);
    p1 = tile(rOut, prim);
    const Vec3 delta = p1 - p0;
    length = delta.norm();
    if (!(length > 0) || !std::isfinite(length)) {
        length = 0;
        return;
    }
    dir = delta / length;
    // Light directions go to reference space through the inverse Jacobian of the tiled map,
    // taken once per span (the mild-deformation assumption again).
    jtInv = tiledJacobianInverse(prim, 0.5 * (rIn + rOut));
    if (!jtInv.allFinite()) jtInv = Mat3::Identity();
    for (std::size_t i = 0; i < scene.lights.size(); ++i) {
        Light& sl = lights[i];
        if (scene.lights[i].type != LightType::Directional) continue;
        double distance;
        sl.directional = true;
        lightAt(scene.lights[i], Vec3::Zero(), sl.lw, distance, sl.e);
        sl.usable = referenceLight(sl.lw, sl.lr);
        if (sl.usable && options.shading == ShadingMode::Fast)
            sl.kernel.emplace(sl.lr, Vec3(-dir), texel.material.shininess, 16, hasSpecular(texel.material));
        if (sl.usable) sl.latticeSlot = shadows.latticeSlot(sl.lw, INFINITY, prim.index);
    }
}

bool SpanContext::referenceLight(const Vec3& lw, Vec3& lr) const {
    lr = jtInv * lw;
    const double len = lr.norm();
    if (!(len > 0) || !std::isfinite(len)) return false;
    lr /= len;
    return true;
}

double SpanMarcher::shadowWidth(const SpanContext& span, double s) const {
    return kShadowConeScale * mConeSpread * (span.tIn + (span.tOut - span.tIn) * (s / span.length));
}

int SpanMarcher::constantShadowLevel(SpanContext& span) const {
    // The width grows linearly along the span and the footprint level with it (monotonically):
    // every query's footprint lies between the ends', so when all of those take the same shadow
    // level (TexelRuntime::shadowLevelFor, which need not be monotone), every query does.
    if (span.shadowLevel == -2) {
        const int first = mShadows.shadowFootprint(span.texel, shadowWidth(span, 0) / span.scale);
        const int last = mShadows.shadowFootprint(span.texel, shadowWidth(span, span.length) / span.scale);
        const int level = span.texel.shadowLevelFor(first);
        span.shadowLevel = level;
        for (int f = std::min(first, last); f <= std::max(first, last); ++f)
            if (span.texel.shadowLevelFor(f) != level) span.shadowLevel = -1;
    }
    return span.shadowLevel;
}

double SpanMarcher::shadowQuery(SpanContext& span, std::size_t i, const Vec3& lw, double distance, VoxelPoint& point,
                                bool record, int& reuseAt, Counters& counters) const {
    SpanContext::ShadowTrack& track = span.tracks[i];
    if (!record)
        if (const int nearest = nearestRecorded(track, point.s, span.shareDistance, reuseAt); nearest >= 0)
            return track.t[std::size_t(nearest)];
    const SpanContext::Light& light = span.lights[i];
    const double width = shadowWidth(span, point.s);
    const Vec3 rc = point.cell();
    double shadow;
    if (light.latticeSlot >= 0) {
        const ShadowQueries::SpanFrame frame{light.lr, span.scale, constantShadowLevel(span)};
        shadow = mShadows.nearAndCachedShadow(light.latticeSlot, span.prim, rc, lw, width, counters, &frame, true);
    } else {
        shadow = mShadows.shadowTransmittance(point.world(), lw, distance, width, &span.prim, rc, counters, true);
    }
    if (record && track.count < SpanContext::kTrackCapacity) {
        track.s[std::size_t(track.count)] = point.s;
        track.t[std::size_t(track.count)] = shadow;
        ++track.count;
    }
    return shadow;
}

primitive::ReflectanceFactors SpanMarcher::reflectance(const SpanContext::Light& light, const Material& m,
                                                       const primitive::SggxMatrix& s, const Vec3& lr,
                                                       const Vec3& view) const {
    if (light.kernel) return (*light.kernel)(s);
    if (mOptions.shading == ShadingMode::Fast) return primitive::reflectanceFast(s, lr, view, m.shininess, 16, hasSpecular(m));
    return primitive::reflectanceReference(s, lr, view, m.shininess, mOptions.referenceSamples);
}

SpanResult SpanMarcher::march(SpanContext& span, int level, bool record, double blendWeight, Counters& counters) const {
    SpanResult r;
    const std::size_t lights = mScene.lights.size();
    PerLight<MarchLight> state(lights);
    const Material& m = span.texel.material;
    const Vec3 view = -span.dir;
    const double shadowRefresh = std::clamp(mOptions.approximations.shadowRefresh, 1e-6, 1.0);
    const double reuseWeight = std::max(mOptions.approximations.lightingReuseWeight, 0.0);
    double reusedShare = 0;
    const double tau = span.texel.tauAt(level);
    ProfileFactor profile(*span.texel.volume, level, span.p0, span.dir);
    counters.voxels += detail::march(*span.texel.volume, level, span.p0, span.dir, span.length,
        [&](const GridVoxel& voxel, double s, double ds) {
            // 1 − exp rather than expm1 (which takes 1.7× as long here): the opacity is only
            // added to and multiplied with quantities of order one, where its absolute error (an
            // ulp of 1) is what counts.
            const double sigma = voxel.extinction(tau, span.dir) * profile(s, ds);
            const double transmit = std::exp(-sigma * ds);
            const double alpha = 1 - transmit;
            if (!(alpha > 0)) return true;
            // Lighting reuse (RenderOptions::approximations.lightingReuseWeight): a voxel with a
            // tiny share of the pixel takes the march's last shadow and reflectance for each light.
            const double share = span.startT * r.transmittance * alpha * blendWeight;
            const bool reuse = share < reuseWeight && reusedShare + share <= ApproximationBudget::kLightingReuseBudget * reuseWeight;
            VoxelPoint point(span, s + 0.5 * ds);
            const Color albedo(voxel.albedo[0], voxel.albedo[1], voxel.albedo[2]);
            Color lk = m.ambient.cwiseProduct(albedo);
            for (std::size_t i = 0; i < lights; ++i) {
                const SpanContext::Light& sl = span.lights[i];
                MarchLight& ml = state[i];
                Vec3 lw = sl.lw;
                double distance = std::numeric_limits<double>::infinity();
                Color e = sl.e;
                if (!sl.directional && !lightAt(mScene.lights[i], point.world(), lw, distance, e)) continue;
                // A shadow query at the first lit voxel, another each time the march's
                // transmittance has fallen below shadowRefresh of what it was at the last one
                // (1, the default: at every absorbing voxel). A reusing voxel takes the last
                // query's shadow and the last reflectance instead (evaluated afresh only if the
                // march has none yet): its light's radiance stays between 0 and the largest a voxel
                // reflects, like the exact one's, so the pixel moves by at most the reused shares'
                // sum times that (ApproximationBudget::lightingReuseWeight). A blend's coarse march
                // records only the queries it takes: the fine march then shares one within a coarse
                // voxel, as before, or takes its own (shareShadowRays). (A march has a reflectance
                // only once it has a shadow: `reused` covers both.)
                const bool reused = reuse && ml.shadowValid;
                if (reused) {
                    reusedShare += share;
                } else if (!ml.shadowValid || r.transmittance < shadowRefresh * ml.shadowAt) {
                    ml.shadow = shadowQuery(span, i, lw, distance, point, record, ml.reuseAt, counters);
                    ml.shadowAt = r.transmittance;
                    ml.shadowValid = true;
                }
                if (ml.shadow <= 0) continue;
                Vec3 lr = sl.lr;
                if (sl.directional ? !sl.usable : !span.referenceLight(lw, lr)) continue;
                if (!reused || !ml.haveReflectance) {
                    ++counters.reflectance;
                    ml.reflectance = reflectance(sl, m, voxel.s, lr, view);
                    ml.haveReflectance = true;
                }
                const primitive::ReflectanceFactors& f = ml.reflectance;
                lk += ml.shadow * e.cwiseProduct(m.diffuse.cwiseProduct(albedo) * f.diffuse + m.specular * f.specular);
            }
            r.radiance += r.transmittance * alpha * lk;
            r.transmittance *= transmit;
            return span.startT * r.transmittance > kTransmittanceCutoff;
        });
    return r;
}

}  // namespace vtex::render::detail
