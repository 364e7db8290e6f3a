/// @file
/// @brief Segment visibility against a texel's source mesh in reference space, through the
/// same Embree BVH the reference renderer traces: what `vtex inspect --source` measures each
/// level's chord transmittance against (octree/chord_transmittance.h).
#pragma once

#include <vtex/ingest/mesh.h>
#include <vtex/octree/volume.h>
#include <vtex/render/geometry.h>

#include <memory>

namespace vtex::render {

namespace detail {
class SourceBvh;
}

class SourceVisibility {
public:
    /// `volume`: where the sampler placed the mesh in the unit cube (a .vtl's or .vto's info). `mesh` must outlive this object.
    SourceVisibility(const ingest::TriangleMesh& mesh, const octree::VolumeInfo& volume);
    ~SourceVisibility();
    SourceVisibility(const SourceVisibility&) = delete;
    SourceVisibility& operator=(const SourceVisibility&) = delete;

    /// Whether no source triangle lies on the reference-space segment a → b. Thread-safe.
    bool visible(const Vec3& a, const Vec3& b) const;

private:
    std::unique_ptr<detail::SourceBvh> mBvh;
};

}  // namespace vtex::render
