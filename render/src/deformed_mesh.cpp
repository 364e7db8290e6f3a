// See deformed_mesh.h.
#include "deformed_mesh.h"

#include "embree_ray.h"

#include <vtex/core/error.h>
#include <vtex/core/memory_budget.h>

#include <embree3/rtcore.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vtex::render::detail {

/// One cell's deformed triangles, before they go into the scene.
struct DeformedMesh::CellOutput {
    std::vector<Eigen::Vector3f> vertices;  // 3 per triangle
    std::vector<std::uint32_t> sourceTriangle;
    std::vector<Eigen::Vector2f> barycentric;  // 3 per triangle
};

namespace {

using CellOutput = DeformedMesh::CellOutput;

// Subdivision stops here whatever the tolerance: 4^8 pieces per source triangle.
constexpr int kMaxSubdivision = 8;

struct ClipVertex {
    Vec3 r;         ///< tiled reference coordinates
    Eigen::Vector2d b;  ///< barycentric (b1, b2) in the source triangle
};

struct ClipPolygon {
    int count = 0;
    std::array<ClipVertex, 16> v;
};

// Keeps the part of `in` where sign·(r[axis] − c) ≥ 0 (Sutherland–Hodgman, one plane).
void clipPlane(const ClipPolygon& in, int axis, double c, double sign, ClipPolygon& out) {
    out.count = 0;
    for (int i = 0; i < in.count; ++i) {
        const ClipVertex& a = in.v[std::size_t(i)];
        const ClipVertex& b = in.v[std::size_t((i + 1) % in.count)];
        const double da = sign * (a.r[axis] - c), db = sign * (b.r[axis] - c);
        if (da >= 0 && out.count < 16) out.v[std::size_t(out.count++)] = a;
        if ((da < 0) != (db < 0) && out.count < 16) {
            const double s = da / (da - db);
            ClipVertex x{a.r + s * (b.r - a.r), a.b + s * (b.b - a.b)};
            x.r[axis] = c;  // exactly on the plane
            out.v[std::size_t(out.count++)] = x;
        }
    }
}

// The whole-unit copies of the reference volume a cell shows: its CellMap's rectangle [lo, hi],
// copies first … end − 1 along x and y.
struct CellTiles {
    explicit CellTiles(const CellMap& map) {
        map.bounds(lo, hi);
        for (int a = 0; a < 2; ++a) {
            first[a] = int(std::floor(lo[a]));
            end[a] = std::max(first[a] + 1, int(std::ceil(hi[a])));
        }
    }
    std::uint64_t count() const { return std::uint64_t(end[0] - first[0]) * std::uint64_t(end[1] - first[1]); }
    Eigen::Vector2d lo, hi;
    int first[2], end[2];
};

class CellDeformer {
public:
    CellDeformer(const TrilinearCell& cell, const CellMap& map, double tolerance, std::uint32_t sourceTriangle,
                 CellOutput& out)
        : mCell(cell), mMap(map), mTolerance(tolerance * cell.size()), mTriangle(sourceTriangle), mOut(out) {}

    void emitPolygon(const ClipPolygon& p) {
        std::array<Corner, 16> corners;
        for (int i = 0; i < p.count; ++i) corners[std::size_t(i)] = corner(p.v[std::size_t(i)].r, p.v[std::size_t(i)].b);
        for (int i = 1; i + 1 < p.count; ++i) subdivide(corners[0], corners[std::size_t(i)], corners[std::size_t(i + 1)], 0);
    }

private:
    // A vertex in tiled reference space, its place in the source triangle, and its world point,
    // mapped once however many sub-triangles share it.
    struct Corner {
        Vec3 r;
        Eigen::Vector2d b;
        Vec3 x;
    };

    Corner corner(const Vec3& r, const Eigen::Vector2d& b) const {
        return {r, b, mCell.map(mMap.toCell(r))};
    }
    Corner midpoint(const Corner& p, const Corner& q) const { return corner(0.5 * (p.r + q.r), 0.5 * (p.b + q.b)); }

    void subdivide(const Corner& a, const Corner& b, const Corner& c, int depth) {
        if ((b.x - a.x).cross(c.x - a.x).squaredNorm() == 0 || (b.r - a.r).cross(c.r - a.r).squaredNorm() == 0) return;
        const Corner ab = midpoint(a, b), bc = midpoint(b, c), ca = midpoint(c, a);
        const Corner centroid = corner((a.r + b.r + c.r) / 3, (a.b + b.b + c.b) / 3);
        // The trilinear map is quadratic along a segment at most (cubic inside): its distance to
        // the flat triangle is largest near the edge midpoints and the centroid.
        const double error = std::max({(ab.x - 0.5 * (a.x + b.x)).norm(), (bc.x - 0.5 * (b.x + c.x)).norm(),
                                       (ca.x - 0.5 * (c.x + a.x)).norm(), (centroid.x - (a.x + b.x + c.x) / 3).norm()});
        if (error <= mTolerance || depth >= kMaxSubdivision || !std::isfinite(error)) {
            for (const Corner* v : {&a, &b, &c}) {
                mOut.vertices.push_back(v->x.cast<float>());
                mOut.barycentric.push_back(v->b.cast<float>());
            }
            mOut.sourceTriangle.push_back(mTriangle);
            return;
        }
        subdivide(a, ab, ca, depth + 1);
        subdivide(ab, b, bc, depth + 1);
        subdivide(ca, bc, c, depth + 1);
        subdivide(ab, bc, ca, depth + 1);
    }

    const TrilinearCell& mCell;
    const CellMap& mMap;
    double mTolerance;
    std::uint32_t mTriangle;
    CellOutput& mOut;
};

// The primitives whose surface carries a texel, and what deforming their sources would make at
// least (every source triangle in every copy a cell shows once; the wrapped copies only add the
// pieces that stick out, so they are not counted in full), and the cells' mean size.
struct TexturedCells {
    std::vector<std::size_t> prims;
    double triangleEstimate = 0;
    double meanSize = 1;
};
TexturedCells texturedCells(const PrimTable& prims, const std::vector<SurfaceRuntime>& surfaces,
                            const std::vector<const SourceBvh*>& sources) {
    TexturedCells out;
    double lengthSum = 0;
    for (std::size_t i = 0; i < prims.size(); ++i) {
        const Prim prim = prims[i];
        const SurfaceRuntime& s = surfaces[std::size_t(prim.surface)];
        if (s.texel < 0) continue;
        out.prims.push_back(i);
        lengthSum += prim.cell.size();
        const SourceBvh& source = *sources[std::size_t(s.texel)];
        const double wraps = double(source.shiftMax()[0] - source.shiftMin()[0] + 1) *
                             double(source.shiftMax()[1] - source.shiftMin()[1] + 1);
        out.triangleEstimate += double(CellTiles(prim.map).count()) * double(source.triangleCount()) * (wraps > 1 ? 1.1 : 1.0);
    }
    if (!out.prims.empty()) out.meanSize = lengthSum / double(out.prims.size());
    return out;
}

// Deforms `source` into the cell of `prim`: each source triangle, in each whole-unit copy of the
// reference volume the cell shows and each of the source's wrap shifts, clipped to that copy
// (within what the cell shows) and subdivided into `out` until within `tolerance`.
void deformInto(const Prim& prim, const SourceBvh& source, double tolerance, CellOutput& out) {
    const CellTiles tiles(prim.map);
    const Eigen::Vector2d bary[3] = {{0, 0}, {1, 0}, {0, 1}};
    for (std::uint32_t t = 0; t < source.triangleCount(); ++t) {
        CellDeformer deformer(prim.cell, prim.map, tolerance, t, out);
        const auto corners = source.triangle(t);
        for (int tj = tiles.first[1]; tj < tiles.end[1]; ++tj)
            for (int ti = tiles.first[0]; ti < tiles.end[0]; ++ti)
                for (int sy = source.shiftMin()[1]; sy <= source.shiftMax()[1]; ++sy)
                    for (int sx = source.shiftMin()[0]; sx <= source.shiftMax()[0]; ++sx) {
                        const Vec3 shift(ti + sx, tj + sy, 0);
                        // The copy [ti, ti + 1) × [tj, tj + 1), within what the cell shows.
                        const Vec3 lo(std::max(double(ti), tiles.lo.x()), std::max(double(tj), tiles.lo.y()), 0);
                        const Vec3 hi(std::min(ti + 1.0, tiles.hi.x()), std::min(tj + 1.0, tiles.hi.y()), 1);
                        ClipPolygon a, b;
                        a.count = 3;
                        bool outside = false;
                        for (int k = 0; k < 3; ++k) a.v[std::size_t(k)] = {corners[std::size_t(k)] + shift, bary[k]};
                        for (int axis = 0; axis < 3 && !outside; ++axis) {
                            clipPlane(a, axis, lo[axis], 1, b);
                            clipPlane(b, axis, hi[axis], -1, a);
                            outside = a.count < 3;
                        }
                        if (!outside) deformer.emitPolygon(a);
                    }
    }
}

}  // namespace

DeformedMesh::DeformedMesh(const PrimTable& prims, const std::vector<SurfaceRuntime>& surfaces,
                           const std::vector<const SourceBvh*>& sources, double tolerance, std::uint64_t maxMemoryBytes,
                           const std::filesystem::path& sceneFile)
    : mSources(sources) {
    const TexturedCells cells = texturedCells(prims, surfaces, sources);
    mLengthScale = cells.meanSize;
    const double maxBytes = maxMemoryBytes > 0 ? double(maxMemoryBytes) : std::numeric_limits<double>::infinity();
    const auto refuse = [&](double triangles) {
        throw MemoryLimitError(sceneFile,
                               "the deformed reference's " + std::to_string(std::uint64_t(triangles)) +
                                   " triangles (--mode embedded needs none)",
                               std::uint64_t(std::min(triangles * kBytesPerTriangle, 1.8e19)), maxMemoryBytes);
    };
    if (cells.triangleEstimate * kBytesPerTriangle > maxBytes) refuse(cells.triangleEstimate);

    // Deformed per cell in parallel, stopping all cells once the triangles pass the limit.
    const double maxTriangles = maxBytes / kBytesPerTriangle;
    std::vector<CellOutput> outputs(cells.prims.size());
    std::atomic<std::uint64_t> total{0};
    std::atomic<bool> over{false};
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, outputs.size()), [&](const tbb::blocked_range<std::size_t>& range) {
        for (std::size_t c = range.begin(); c != range.end() && !over.load(std::memory_order_relaxed); ++c) {
            const Prim prim = prims[cells.prims[c]];
            deformInto(prim, *sources[std::size_t(surfaces[std::size_t(prim.surface)].texel)], tolerance, outputs[c]);
            if (double(total += outputs[c].sourceTriangle.size()) > maxTriangles) over = true;
        }
    });
    if (over) refuse(double(total.load()));
    std::vector<int> texelOfCell(outputs.size());
    for (std::size_t c = 0; c < outputs.size(); ++c) texelOfCell[c] = surfaces[std::size_t(prims[cells.prims[c]].surface)].texel;
    buildScene(outputs, texelOfCell);
}

void DeformedMesh::buildScene(std::vector<CellOutput>& outputs, const std::vector<int>& texelOfCell) {
    std::uint64_t count = 0;
    for (const CellOutput& out : outputs) count += out.sourceTriangle.size();
    mSourceTriangle.reserve(count);
    mTexel.reserve(count);
    mBarycentric.reserve(3 * count);

    RTCDevice device = rtcNewDevice(nullptr);
    if (!device) throw std::runtime_error("Embree: cannot create a device");
    mDevice = ownDevice(device);
    RTCScene scene = rtcNewScene(device);
    mScene = ownScene(scene);
    rtcSetSceneFlags(scene, RTC_SCENE_FLAG_ROBUST);
    if (count > 0) {
        RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
        auto* vertices = static_cast<float*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                                                     3 * sizeof(float), 3 * count));
        auto* indices = static_cast<std::uint32_t*>(rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                                                            3 * sizeof(std::uint32_t), count));
        if (!vertices || !indices) {
            rtcReleaseGeometry(geometry);
            throw std::runtime_error("Embree: cannot allocate the deformed meshes");
        }
        std::size_t v = 0;
        for (std::size_t c = 0; c < outputs.size(); ++c) {
            CellOutput& out = outputs[c];
            for (const Eigen::Vector3f& x : out.vertices) {
                for (int a = 0; a < 3; ++a) vertices[3 * v + std::size_t(a)] = x[a];
                indices[v] = std::uint32_t(v);
                ++v;
            }
            mSourceTriangle.insert(mSourceTriangle.end(), out.sourceTriangle.begin(), out.sourceTriangle.end());
            mTexel.insert(mTexel.end(), out.sourceTriangle.size(), std::uint32_t(texelOfCell[c]));
            mBarycentric.insert(mBarycentric.end(), out.barycentric.begin(), out.barycentric.end());
            out = CellOutput{};  // release as we go: the peak stays near one copy
        }
        rtcCommitGeometry(geometry);
        rtcAttachGeometry(scene, geometry);
        rtcReleaseGeometry(geometry);
    }
    rtcCommitScene(scene);
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE) throw std::runtime_error("Embree: cannot build the deformed meshes' BVH");
}

DeformedMesh::~DeformedMesh() = default;

double DeformedMesh::selfIntersectionGap(const Vec3& o) const {
    // Float vertices put a triangle within ~1e-7 of its coordinates of where the double hit
    // point says it is: a gap ten times that keeps a ray from finding its own triangle again.
    return 1e-6 * (o.cwiseAbs().maxCoeff() + mLengthScale);
}

std::optional<DeformedMesh::Hit> DeformedMesh::intersect(const Vec3& o, const Vec3& d, double tNear, double tFar) const {
    if (mSourceTriangle.empty() || !embreeCanTrace(o, d)) return std::nullopt;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRayHit rayhit = embreeRayHit(o, d, tNear, tFar);
    rtcIntersect1(static_cast<RTCScene>(mScene.get()), &context, &rayhit);
    if (rayhit.hit.geomID == RTC_INVALID_GEOMETRY_ID) return std::nullopt;
    const std::size_t t = rayhit.hit.primID;
    Hit hit;
    hit.t = rayhit.ray.tfar;
    const Vec3 n(rayhit.hit.Ng_x, rayhit.hit.Ng_y, rayhit.hit.Ng_z);
    const double length = n.norm();
    hit.normal = length > 0 && std::isfinite(length) ? Vec3(n / length) : Vec3(-d);
    const double u = rayhit.hit.u, v = rayhit.hit.v;
    const Eigen::Vector2d b = (1 - u - v) * mBarycentric[3 * t].cast<double>() + u * mBarycentric[3 * t + 1].cast<double>() +
                              v * mBarycentric[3 * t + 2].cast<double>();
    hit.texel = int(mTexel[t]);
    hit.albedo = mSources[mTexel[t]]->albedo(mSourceTriangle[t], b.x(), b.y());
    return hit;
}

bool DeformedMesh::occluded(const Vec3& o, const Vec3& d, double tNear, double tFar) const {
    if (mSourceTriangle.empty() || !embreeCanTrace(o, d)) return false;
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray = embreeRay(o, d, std::max(tNear, selfIntersectionGap(o)), tFar);
    if (!(ray.tnear < ray.tfar)) return false;
    rtcOccluded1(static_cast<RTCScene>(mScene.get()), &context, &ray);
    return ray.tfar < 0;
}

}  // namespace vtex::render::detail
