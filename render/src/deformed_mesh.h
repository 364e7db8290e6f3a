// `vtex reference --mode deformed`: every cell's copy of its texel's source mesh, clipped to the
// cell, deformed by the cell's trilinear map and subdivided until the map is linear on each
// triangle to a tolerance, in one world-space Embree BVH. Embree types stay in the .cpp.
#pragma once

#include "embree_handle.h"
#include "frame.h"
#include "source_bvh.h"

#include <cstdint>
#include <filesystem>
#include <optional>
#include <vector>

namespace vtex::render::detail {

class DeformedMesh {
public:
    struct Hit {
        double t = 0;
        Vec3 normal;     ///< unit geometric normal, world (either side)
        Color albedo;
        int texel = -1;
    };

    /// `sources[k]` is texel k's source (nullptr for texels no surface uses). `tolerance`: the
    /// largest distance between a triangle and the deformed surface it stands for, as a
    /// fraction of its cell's size. Throws vtex::MemoryLimitError naming `sceneFile` when the
    /// triangles would take more than `maxMemoryBytes` (0: no limit): before building when the source triangles
    /// alone exceed it, during subdivision otherwise (nothing large is kept either way).
    DeformedMesh(const PrimTable& prims, const std::vector<SurfaceRuntime>& surfaces,
                 const std::vector<const SourceBvh*>& sources, double tolerance, std::uint64_t maxMemoryBytes,
                 const std::filesystem::path& sceneFile);
    ~DeformedMesh();
    DeformedMesh(const DeformedMesh&) = delete;
    DeformedMesh& operator=(const DeformedMesh&) = delete;

    std::optional<Hit> intersect(const Vec3& o, const Vec3& d, double tNear, double tFar) const;
    /// Whether a triangle lies on o + t·d, t ∈ (tNear, tFar); tNear is raised above the float
    /// rounding of the triangles around o, so that a ray leaving a triangle does not hit it.
    bool occluded(const Vec3& o, const Vec3& d, double tNear, double tFar) const;

    std::uint64_t triangleCount() const { return mSourceTriangle.size(); }

    /// Memory per deformed triangle, as estimated against the limit: Embree's unshared
    /// vertices, indices and BVH, plus what a hit needs to find its colour.
    static constexpr double kBytesPerTriangle = 160;

    /// One cell's deformed triangles while the constructor makes them (deformed_mesh.cpp).
    struct CellOutput;

private:
    /// The Embree scene of the cells' triangles (`texelOfCell[c]`: cell c's texel), each cell's
    /// output released as it is copied.
    void buildScene(std::vector<CellOutput>& outputs, const std::vector<int>& texelOfCell);
    double selfIntersectionGap(const Vec3& o) const;

    const std::vector<const SourceBvh*>& mSources;
    std::vector<std::uint32_t> mSourceTriangle;
    std::vector<std::uint32_t> mTexel;
    std::vector<Eigen::Vector2f> mBarycentric;  ///< 3 per triangle: (b1, b2) in the source triangle
    double mLengthScale = 1;
    EmbreeHandle mDevice{nullptr, nullptr};
    EmbreeHandle mScene{nullptr, nullptr};
};

}  // namespace vtex::render::detail
