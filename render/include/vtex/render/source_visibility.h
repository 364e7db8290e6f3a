/// @file
/// @brief Segment visibility against a texel's source mesh in reference space, through the
/// same Embree BVH the reference renderer traces: what `vtex inspect --source`, `vtex build
/// --source` and a pipeline's build stage measure each level's transmittance against
/// (octree/chord_transmittance.h).
#pragma once

#include <vtex/ingest/mesh.h>
#include <vtex/octree/chord_transmittance.h>
#include <vtex/octree/volume.h>
#include <vtex/render/geometry.h>

#include <memory>
#include <vector>

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

/// How faithful each level of a texel is to its source mesh (issue 13's measure): the
/// transmittance along 4096 random chords of the whole texel, and over 256 beams of the level
/// (mean, mean |error| and 95th percentile).
struct SourceFidelity {
    std::vector<octree::ChordTransmittance> chords;
    std::vector<octree::BeamError> beams;
};
SourceFidelity measureSourceFidelity(const octree::Octree& tree, const ingest::TriangleMesh& source);

}  // namespace vtex::render
