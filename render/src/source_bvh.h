// A texel's source mesh in reference space, behind one Embree triangle BVH: what the reference
// renderer traces instead of the octree. Embree types stay in source_bvh.cpp.
#pragma once

#include <vtex/ingest/mesh.h>
#include <vtex/octree/volume.h>
#include <vtex/render/geometry.h>
#include <vtex/render/scene.h>

#include "embree_handle.h"

#include <array>
#include <cstdint>
#include <memory>
#include <optional>
#include <vector>

namespace vtex::render::detail {

struct SourceHit {
    double s = 0;       ///< where along the segment, as a fraction of it
    Vec3 normal;        ///< unit geometric normal of the triangle, reference space (either side)
    Color albedo;       ///< linear base colour at the hit
};

/// Shadow rays skip this much reference space (1e-5 of the unit cube, under a hundredth of a
/// voxel at 1024³) from where they leave a source triangle: far above the float rounding of the
/// BVH, far below any feature the sampler can resolve.
inline constexpr double kSelfIntersectionGap = 1e-5;

/// The source mesh placed into the unit cube as the sampler placed it (p·scale + offset).
/// Segments are given in tiled reference coordinates (a surface's `repeat` copies side by side
/// along x and y) and cut where they cross from one copy to the next. A cyclic volume's mesh
/// wraps around in x and y as the sampler wrapped it: the parts that stick out of the cube are
/// seen from the other side, through instances of the one BVH shifted by whole units.
class SourceBvh {
public:
    SourceBvh(const ingest::TriangleMesh& mesh, const octree::VolumeInfo& volume);
    ~SourceBvh();
    SourceBvh(const SourceBvh&) = delete;
    SourceBvh& operator=(const SourceBvh&) = delete;

    /// The first triangle on p0 + s·(p1 − p0), s ∈ (sMin, 1].
    std::optional<SourceHit> intersect(const Vec3& p0, const Vec3& p1, double sMin) const;
    /// Whether any triangle lies on p0 + s·(p1 − p0), s ∈ (sMin, 1].
    bool occluded(const Vec3& p0, const Vec3& p1, double sMin) const;
    /// occluded(), the first kSelfIntersectionGap skipped when the segment leaves a source hit at
    /// p0 (a shadow ray from a shaded triangle) so that the triangle does not shadow itself.
    bool occludedLeaving(const Vec3& p0, const Vec3& p1, bool leavesAHit) const {
        const double length = (p1 - p0).norm();
        return occluded(p0, p1, leavesAHit ? (length > 0 ? kSelfIntersectionGap / length : 1.0) : 0.0);
    }

    std::uint64_t triangleCount() const { return mMesh.triangles.size(); }
    bool cyclic() const { return mCyclic; }
    /// The reference-space corners of triangle t.
    std::array<Vec3, 3> triangle(std::uint32_t t) const;
    /// Linear base colour at barycentric (b1, b2) of triangle t (corner 1 and 2 weights).
    Color albedo(std::uint32_t t, double b1, double b2) const;
    /// The range of whole-unit shifts along x and y under which some part of the mesh lands in
    /// the unit square (only [0, 0] for a volume that is not cyclic).
    std::array<int, 2> shiftMin() const { return mShiftMin; }
    std::array<int, 2> shiftMax() const { return mShiftMax; }

private:
    template <class Visit>
    bool forEachPiece(const Vec3& p0, const Vec3& p1, double sMin, Visit&& visit) const;

    const ingest::TriangleMesh& mMesh;
    std::vector<Vec3> mPositions;  ///< reference space, double
    bool mCyclic = false;
    std::array<int, 2> mShiftMin{0, 0}, mShiftMax{0, 0};
    EmbreeHandle mDevice{nullptr, nullptr};
    EmbreeHandle mMeshScene{nullptr, nullptr};  ///< the triangles
    EmbreeHandle mInstances{nullptr, nullptr};  ///< the shifted copies of a cyclic mesh, if any
    void* mTraced = nullptr;                    ///< mInstances when there are any, else mMeshScene
};

}  // namespace vtex::render::detail
