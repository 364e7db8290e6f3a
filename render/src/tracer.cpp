// Embree 3 user geometry over bilinear patches and trilinear cells (see tracer.h).
//
// Embree traverses its float BVH with the float copy of the ray; the primitive tests run in
// double precision on the caller's double ray, which travels in an extended intersect context
// (the documented Embree 3 way to pass per-ray data to user geometry callbacks).
#include "tracer.h"

#include "embree_ray.h"

#include <vtex/core/error.h>

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace vtex::render::detail {
namespace {

struct TraceContext {
    RTCIntersectContext context;  // first member: Embree hands back a pointer to it
    const PrimTable* prims;
    Vec3 o, d;
    double tNear;
    double tBest;
    Hit best;
    SpanCache* cache;
};

// Grows [lo, hi] by the exact (double) bounds of primitive i: a bilinear patch lies in the convex
// hull of its corners, a trilinear cell in that of its eight corners.
void includeBounds(const PrimTable& prims, std::size_t i, Vec3& lo, Vec3& hi) {
    const auto include = [&](const auto& corners) {
        for (const Vec3& c : corners) {
            lo = lo.cwiseMin(c);
            hi = hi.cwiseMax(c);
        }
    };
    if (prims.textured(i))
        include(prims.cell(i).corners());
    else
        include(prims.patch(i));
}

void boundsFunction(const RTCBoundsFunctionArguments* args) {
    const auto& prims = *static_cast<const PrimTable*>(args->geometryUserPtr);
    Vec3 lo = Vec3::Constant(INFINITY), hi = Vec3::Constant(-INFINITY);
    includeBounds(prims, args->primID, lo, hi);
    // Pad for the float rounding of the box and of the ray Embree traverses with.
    const double pad = 1e-6 * (lo.cwiseAbs().maxCoeff() + hi.cwiseAbs().maxCoeff() + (hi - lo).maxCoeff()) + 1e-30;
    RTCBounds* b = args->bounds_o;
    b->lower_x = std::nextafter(float(lo.x() - pad), -INFINITY);
    b->lower_y = std::nextafter(float(lo.y() - pad), -INFINITY);
    b->lower_z = std::nextafter(float(lo.z() - pad), -INFINITY);
    b->upper_x = std::nextafter(float(hi.x() + pad), INFINITY);
    b->upper_y = std::nextafter(float(hi.y() + pad), INFINITY);
    b->upper_z = std::nextafter(float(hi.z() + pad), INFINITY);
}

void intersectFunction(const RTCIntersectFunctionNArguments* args) {
    if (!args->valid[0]) return;
    auto* ctx = reinterpret_cast<TraceContext*>(args->context);
    const PrimTable& prims = *ctx->prims;
    auto* rayhit = reinterpret_cast<RTCRayHit*>(args->rayhit);  // N = 1: rtcIntersect1 only
    Hit hit;
    hit.prim = int(args->primID);
    if (!prims.textured(args->primID)) {
        const auto p = prims.patch(args->primID);
        const auto h = intersectBilinearPatch(ctx->o, ctx->d, p[0], p[1], p[2], p[3], ctx->tNear, ctx->tBest);
        if (!h) return;
        hit.t = h->t;
        hit.u = h->u;
        hit.v = h->v;
    } else {
        SpanCache local;  // a ray traced without a cache: one for this test alone
        SpanCache* cache = ctx->cache ? ctx->cache : &local;
        const std::array<CellSpan, 4>* spansPtr = nullptr;
        int count = 0;
        for (int i = 0; i < cache->used; ++i)
            if (cache->prim[std::size_t(i)] == int(args->primID)) {
                spansPtr = &cache->read(std::size_t(i));
                count = cache->count[std::size_t(i)];
                break;
            }
        if (!spansPtr) {
            const std::size_t slot = std::size_t(cache->next);
            SpanCache::Spans& spans = cache->write(slot);
            cache->count[slot] = count = cellSpans(prims.cell(args->primID), ctx->o, ctx->d, spans);
            cache->prim[slot] = int(args->primID);
            spansPtr = &spans;
            cache->next = (cache->next + 1) % SpanCache::kSize;
            cache->used = std::min(cache->used + 1, SpanCache::kSize);
        }
        const std::array<CellSpan, 4>& spans = *spansPtr;
        int chosen = -1;
        for (int i = 0; i < count; ++i) {
            if (spans[std::size_t(i)].tOut > ctx->tNear) {
                chosen = i;
                break;
            }
        }
        if (chosen < 0) return;
        hit.span = spans[std::size_t(chosen)];
        hit.t = std::max(hit.span.tIn, ctx->tNear);
        if (!(hit.t < ctx->tBest)) return;
    }
    ctx->tBest = hit.t;
    ctx->best = hit;
    rayhit->ray.tfar = std::nextafter(float(hit.t), INFINITY);
    rayhit->hit.u = 0;
    rayhit->hit.v = 0;
    rayhit->hit.Ng_x = 0;
    rayhit->hit.Ng_y = 0;
    rayhit->hit.Ng_z = 1;
    rayhit->hit.primID = args->primID;
    rayhit->hit.geomID = args->geomID;
    rayhit->hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
}

void errorFunction(void*, RTCError code, const char* message) {
    (void)code;
    (void)message;  // reported by rtcGetDeviceError where it matters
}

}  // namespace

Tracer::Tracer(PrimTable prims) : mPrims(std::move(prims)) {
    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("Embree: cannot create a device");
    rtcSetDeviceErrorFunction(device, errorFunction, nullptr);
    RTCScene scene = rtcNewScene(device);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(scene, RTC_BUILD_QUALITY_HIGH);
    if (!mPrims.empty()) {
        for (std::size_t i = 0; i < mPrims.size(); ++i) includeBounds(mPrims, i, mLo, mHi);
        mHair = 1e-9 * (mLo.cwiseAbs().cwiseMax(mHi.cwiseAbs()).maxCoeff() + (mHi - mLo).maxCoeff());
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_USER);
        rtcSetGeometryUserPrimitiveCount(geometry, unsigned(mPrims.size()));
        rtcSetGeometryUserData(geometry, &mPrims);
        rtcSetGeometryBoundsFunction(geometry, boundsFunction, &mPrims);
        rtcSetGeometryIntersectFunction(geometry, intersectFunction);
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(scene, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) {
        rtcReleaseScene(scene);
        rtcReleaseDevice(device);
        throw std::runtime_error("Embree: cannot build the scene");
    }
    mDevice = device;
    mScene = scene;
}

Tracer::~Tracer() {
    rtcReleaseScene(static_cast<RTCScene>(mScene));
    rtcReleaseDevice(static_cast<RTCDevice>(mDevice));
}

// The slab test of the ray against the bounds, in double precision. A shadow ray toward a light
// above the scene, from the top of a texel's shell (a lattice node's that leaves its cell
// through the top), is inside the bounds for a rounding error only; Embree would still descend
// to the cells around its origin and test them (7 % of the bush field's far view).
bool Tracer::mayHit(const Vec3& o, const Vec3& d, double tNear, double tFar) const {
    double t0 = tNear, t1 = tFar;
    for (int k = 0; k < 3; ++k) {
        if (d[k] == 0) {
            if (o[k] < mLo[k] || o[k] > mHi[k]) return false;
            continue;
        }
        const double inv = 1 / d[k];
        double a = (mLo[k] - o[k]) * inv, b = (mHi[k] - o[k]) * inv;
        if (a > b) std::swap(a, b);
        t0 = std::max(t0, a);
        t1 = std::min(t1, b);
    }
    return t1 >= t0 && t1 > tNear + mHair / d.norm();
}

std::optional<Hit> Tracer::trace(const Vec3& o, const Vec3& d, double tNear, double tFar, SpanCache* cache) const {
    if (!embreeCanTrace(o, d)) return std::nullopt;  // Embree would assert (embree_ray.h)
    if (mPrims.empty() || !mayHit(o, d, tNear, tFar)) return std::nullopt;
    TraceContext ctx;
    rtcInitIntersectContext(&ctx.context);
    ctx.prims = &mPrims;
    ctx.o = o;
    ctx.d = d;
    ctx.tNear = tNear;
    ctx.tBest = tFar;
    ctx.cache = cache;
    RTCRayHit rayhit;
    rayhit.ray.org_x = float(o.x());
    rayhit.ray.org_y = float(o.y());
    rayhit.ray.org_z = float(o.z());
    rayhit.ray.dir_x = float(d.x());
    rayhit.ray.dir_y = float(d.y());
    rayhit.ray.dir_z = float(d.z());
    // Embree culls boxes with the float interval: open it a little so that the double tests
    // decide, not the float rounding of tNear and of the origin.
    rayhit.ray.tnear = float(std::max(0.0, tNear * (1 - 1e-5) - 1e-6 * std::abs(tNear)));
    rayhit.ray.tfar = std::isfinite(tFar) ? std::nextafter(float(tFar), INFINITY) : INFINITY;
    rayhit.ray.mask = 0xFFFFFFFFu;
    rayhit.ray.time = 0;
    rayhit.ray.flags = 0;
    rayhit.ray.id = 0;
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    rtcIntersect1(static_cast<RTCScene>(mScene), &ctx.context, &rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID || ctx.best.prim < 0) return std::nullopt;
    return ctx.best;
}

}  // namespace vtex::render::detail
