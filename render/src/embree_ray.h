// An Embree 3 ray from a double-precision one, what every rtcIntersect1 / rtcOccluded1 call of
// the reference renderer starts from; and the owning handles of its devices and scenes.
#pragma once

#include <vtex/render/geometry.h>

#include "embree_handle.h"

#include <embree3/rtcore.h>

#include <cmath>

namespace vtex::render::detail {

/// Whether Embree 3 can take a ray from `origin` along `direction`: it asserts on a component
/// that is not finite or beyond ±1.844e18 (FLT_LARGE). Every trace and occlusion query checks
/// this first and treats a ray it cannot take as a miss; scenes are refused long before
/// (frame.h, kMaxSceneCoordinate), so only a ray gone astray can fail it.
inline bool embreeCanTrace(const Vec3& origin, const Vec3& direction) {
    constexpr double kLimit = 1e18;
    return origin.allFinite() && direction.allFinite() && origin.cwiseAbs().maxCoeff() < kLimit &&
           direction.cwiseAbs().maxCoeff() < kLimit;
}

inline RTCRay embreeRay(const Vec3& origin, const Vec3& direction, double tNear, double tFar) {
    RTCRay ray;
    ray.org_x = float(origin.x());
    ray.org_y = float(origin.y());
    ray.org_z = float(origin.z());
    ray.dir_x = float(direction.x());
    ray.dir_y = float(direction.y());
    ray.dir_z = float(direction.z());
    ray.tnear = float(tNear);
    ray.tfar = std::isfinite(tFar) ? float(tFar) : INFINITY;
    ray.mask = 0xFFFFFFFFu;
    ray.time = 0;
    ray.flags = 0;
    ray.id = 0;
    return ray;
}

inline RTCRayHit embreeRayHit(const Vec3& origin, const Vec3& direction, double tNear, double tFar) {
    RTCRayHit rayhit;
    rayhit.ray = embreeRay(origin, direction, tNear, tFar);
    rayhit.hit.geomID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.primID = RTC_INVALID_GEOMETRY_ID;
    rayhit.hit.instID[0] = RTC_INVALID_GEOMETRY_ID;
    return rayhit;
}

inline EmbreeHandle ownDevice(RTCDevice device) {
    return {device, [](void* p) { rtcReleaseDevice(static_cast<RTCDevice>(p)); }};
}

inline EmbreeHandle ownScene(RTCScene scene) {
    return {scene, [](void* p) { rtcReleaseScene(static_cast<RTCScene>(p)); }};
}

}  // namespace vtex::render::detail
