// See source_bvh.h.
#include "source_bvh.h"

#include <vtex/ingest/ingest.h>

#include "embree_ray.h"

#include <embree3/rtcore.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vtex::render::detail {
namespace {

// How far a mesh may stick out of the unit square and still be wrapped: the sampler wraps any
// amount, but a part several units out is a mistake in the source, not a texel.
constexpr int kMaxShift = 4;

}  // namespace

SourceBvh::SourceBvh(const ingest::TriangleMesh& mesh, const octree::VolumeInfo& volume)
    : mMesh(mesh), mCyclic(volume.cyclic) {
    mPositions.reserve(mesh.positions.size());
    Vec3 lo = Vec3::Constant(std::numeric_limits<double>::infinity()), hi = -lo;
    for (const auto& p : mesh.positions) {
        Vec3 r;
        for (int a = 0; a < 3; ++a) r[a] = double(p[a]) * volume.scale + volume.offset[std::size_t(a)];
        mPositions.push_back(r);
        lo = lo.cwiseMin(r);
        hi = hi.cwiseMax(r);
    }
    if (mCyclic && !mesh.positions.empty()) {
        // A part at x ∈ [k, k+1) shows in the unit square under the shift −k.
        for (int a = 0; a < 2; ++a) {
            mShiftMin[std::size_t(a)] = -std::clamp(int(std::floor(hi[a])), -kMaxShift, kMaxShift);
            mShiftMax[std::size_t(a)] = -std::clamp(int(std::floor(lo[a])), -kMaxShift, kMaxShift);
        }
    }

    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("Embree: cannot create a device");
    mDevice = ownDevice(device);
    RTCScene meshScene = rtcNewScene(device);
    mMeshScene = ownScene(meshScene);
    rtcSetSceneFlags(meshScene, RTC_SCENE_FLAG_ROBUST);
    rtcSetSceneBuildQuality(meshScene, RTC_BUILD_QUALITY_HIGH);
    if (!mesh.triangles.empty()) {
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                     3 * sizeof(float), mPositions.size()));
        auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                            3 * sizeof(std::uint32_t), mesh.triangles.size()));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            throw std::runtime_error("Embree: cannot allocate the source mesh");
        }
        for (std::size_t i = 0; i < mPositions.size(); ++i)
            for (int a = 0; a < 3; ++a) vertices[3 * i + std::size_t(a)] = float(mPositions[i][a]);
        for (std::size_t t = 0; t < mesh.triangles.size(); ++t)
            for (int k = 0; k < 3; ++k) indices[3 * t + std::size_t(k)] = mesh.triangles[t][std::size_t(k)];
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(meshScene, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(meshScene);
    mTraced = meshScene;
    if (mCyclic && (mShiftMin != std::array<int, 2>{0, 0} || mShiftMax != std::array<int, 2>{0, 0})) {
        RTCScene top = rtcNewScene(device);
        mInstances = ownScene(top);
        for (int sy = mShiftMin[1]; sy <= mShiftMax[1]; ++sy)
            for (int sx = mShiftMin[0]; sx <= mShiftMax[0]; ++sx) {
                RTCGeometry instance = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_INSTANCE);
                rtcSetGeometryInstancedScene(instance, meshScene);
                const float transform[12] = {1, 0, 0, 0, 1, 0, 0, 0, 1, float(sx), float(sy), 0};
                rtcSetGeometryTransform(instance, 0, RTC_FORMAT_FLOAT3X4_COLUMN_MAJOR, transform);
                rtcCommitGeometry(instance);
                rtcAttachGeometry(top, instance);
                rtcReleaseGeometry(instance);
            }
        rtcCommitScene(top);
        mTraced = top;
    }
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: cannot build the source mesh's BVH");
}

SourceBvh::~SourceBvh() = default;

// Calls visit(origin, tMin, tMax) for the pieces of the segment inside each copy of the unit
// square, in order along it, with the origin moved into that copy; stops when visit returns true.
template <class Visit>
bool SourceBvh::forEachPiece(const Vec3& p0, const Vec3& p1, double sMin, Visit&& visit) const {
    const Vec3 delta = p1 - p0;
    // Crossings of whole x and y values, in order: two sorted runs merged.
    auto crossings = [&](int axis, double& next, double& step) {
        if (delta[axis] == 0) {
            next = step = std::numeric_limits<double>::infinity();
            return;
        }
        const double k = delta[axis] > 0 ? std::floor(p0[axis]) + 1 : std::ceil(p0[axis]) - 1;
        next = (k - p0[axis]) / delta[axis];
        step = 1 / std::abs(delta[axis]);
    };
    double nextX, stepX, nextY, stepY;
    crossings(0, nextX, stepX);
    crossings(1, nextY, stepY);
    double s = 0;
    while (s < 1) {
        const double end = std::min({nextX, nextY, 1.0});
        if (end > sMin && end > s) {
            const Vec3 mid = p0 + (0.5 * (s + end)) * delta;
            const Vec3 shift(std::floor(mid.x()), std::floor(mid.y()), 0);
            if (visit(Vec3(p0 - shift), std::max(s, sMin), end)) return true;
        }
        if (end >= 1) break;
        if (nextX <= end) nextX += stepX;
        if (nextY <= end) nextY += stepY;
        s = end;
    }
    return false;
}

std::optional<SourceHit> SourceBvh::intersect(const Vec3& p0, const Vec3& p1, double sMin) const {
    if (mMesh.triangles.empty()) return std::nullopt;
    const Vec3 delta = p1 - p0;
    std::optional<SourceHit> result;
    forEachPiece(p0, p1, sMin, [&](const Vec3& origin, double s0, double s1) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        if (!embreeCanTrace(origin, delta)) return false;
        RTCRayHit rayhit = embreeRayHit(origin, delta, s0, s1);
        rtcIntersect1(static_cast<RTCScene>(mTraced), &context, &rayhit);
        if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return false;
        const std::uint32_t t = rayhit.hit.primID;
        const auto corners = triangle(t);
        Vec3 n = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
        const double length = n.norm();
        SourceHit hit;
        hit.s = std::clamp(double(rayhit.ray.tfar), s0, s1);
        hit.normal = length > 0 && std::isfinite(length) ? Vec3(n / length) : Vec3(0, 0, 1);
        hit.albedo = albedo(t, rayhit.hit.u, rayhit.hit.v);
        result = hit;
        return true;
    });
    return result;
}

bool SourceBvh::occluded(const Vec3& p0, const Vec3& p1, double sMin) const {
    if (mMesh.triangles.empty()) return false;
    const Vec3 delta = p1 - p0;
    return forEachPiece(p0, p1, sMin, [&](const Vec3& origin, double s0, double s1) {
        RTCIntersectContext context;
        rtcInitIntersectContext(&context);
        if (!embreeCanTrace(origin, delta)) return false;
        RTCRay ray = embreeRay(origin, delta, s0, s1);
        rtcOccluded1(static_cast<RTCScene>(mTraced), &context, &ray);
        return ray.tfar < 0;  // Embree marks an occluded ray with tfar = −∞
    });
}

std::array<Vec3, 3> SourceBvh::triangle(std::uint32_t t) const {
    const auto& tri = mMesh.triangles[t];
    return {mPositions[tri[0]], mPositions[tri[1]], mPositions[tri[2]]};
}

Color SourceBvh::albedo(std::uint32_t t, double b1, double b2) const {
    const std::size_t m = mMesh.triangleMaterials.empty() ? 0 : mMesh.triangleMaterials[t];
    if (m >= mMesh.materials.size()) return Color::Ones();
    const ingest::Material& material = mMesh.materials[m];
    Color colour = material.baseColorFactor.head<3>().cast<double>();
    const int texture = material.baseColorTexture;
    if (texture >= 0 && std::size_t(texture) < mMesh.textures.size() && mMesh.uvs.size() == mMesh.positions.size()) {
        const auto& tri = mMesh.triangles[t];
        const Eigen::Vector2f uv = float(1 - b1 - b2) * mMesh.uvs[tri[0]] + float(b1) * mMesh.uvs[tri[1]] +
                                   float(b2) * mMesh.uvs[tri[2]];
        colour = colour.cwiseProduct(ingest::sampleBaseColour(mMesh.textures[std::size_t(texture)], uv.x(), uv.y()).cast<double>());
    }
    return colour;
}

}  // namespace vtex::render::detail
