// See source_visibility.h.
#include <vtex/render/source_visibility.h>

#include "source_bvh.h"

namespace vtex::render {

SourceVisibility::SourceVisibility(const ingest::TriangleMesh& mesh, const octree::VolumeInfo& volume)
    : mBvh(std::make_unique<detail::SourceBvh>(mesh, volume)) {}

SourceVisibility::~SourceVisibility() = default;

bool SourceVisibility::visible(const Vec3& a, const Vec3& b) const { return !mBvh->occluded(a, b, 0); }

SourceFidelity measureSourceFidelity(const octree::Octree& tree, const ingest::TriangleMesh& source) {
    const SourceVisibility visibility(source, tree.info.source);
    const auto visible = [&](const Vec3& a, const Vec3& b) { return visibility.visible(a, b); };
    return {octree::measureChordTransmittance(tree, visible), octree::measureBeamTransmittance(tree, visible)};
}

}  // namespace vtex::render
