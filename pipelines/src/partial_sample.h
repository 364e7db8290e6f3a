// The sample stage of `vtex run` re-sampling only where its source changed (issue 13, "partial
// recompute"): the stage keeps, beside its volume, a copy of the mesh it sampled; when the
// source changes, the triangles that differ between that copy and the new mesh give the region
// (sampler::changedRegion) that sampler::updateRegion samples again; the build stage after it
// then resumes its earlier octree and filters again only that region's ancestors. Internal to
// vtex_pipelines.
#pragma once

#include <vtex/ingest/mesh.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/sampler/sampler.h>

#include <filesystem>
#include <optional>
#include <string>

namespace vtex::pipelines::detail {

/// The stage's earlier run, as its manifest recorded it.
struct EarlierSample {
    std::filesystem::path manifest;    ///< samples/NAME.manifest.json
    std::filesystem::path volume;      ///< the .vtl it wrote
    std::filesystem::path sampledMesh;  ///< the copy of the mesh it sampled
    std::string parameters;            ///< what the stage's key holds besides the mesh (sampleParameters)
};

struct SampleResult {
    octree::SparseVolume volume;
    /// The region re-sampled; empty: sampled in full.
    std::optional<octree::VoxelBox> region;
    /// With a region: the content hash of the earlier volume it started from.
    std::string updatedFrom;
};

/// `mesh` sampled with `options`: by updateRegion when the earlier run's manifest names
/// `earlier.parameters`, its volume and mesh copy have the content it recorded, and the change
/// allows a region smaller than half the volume; in full otherwise (no earlier run, another
/// resolution, a damaged or foreign file, a material, texture or mapping changed, a solid
/// interior). The result is the full sampling's either way.
SampleResult sampleOrUpdate(const ingest::TriangleMesh& mesh, const sampler::SampleOptions& options,
                            const EarlierSample& earlier, Progress& progress);

/// The build stage's earlier run. Its manifest's details hold `parameters` (the filter and
/// tolerance) and `volume`, the content hash of the volume it built.
struct EarlierBuild {
    std::filesystem::path manifest;  ///< builds/NAME.manifest.json
    std::filesystem::path octree;    ///< the .vto it wrote
    std::string parameters;
};

/// The octree of `volume`: the earlier build's tree resumed (octree::OctreeBuilder::resume) and
/// only `region` filtered again when the sample stage re-sampled that region of the very volume
/// the earlier build built (`updatedFrom`), the earlier build's manifest vouches for its octree
/// and names the same parameters, and the tree allows it; a full build otherwise. The same tree
/// either way; `updated` says which.
octree::Octree buildOrUpdate(octree::SparseVolume volume, const octree::BuildOptions& options,
                             const std::optional<octree::VoxelBox>& region, const std::string& updatedFrom,
                             const EarlierBuild& earlier, Progress& progress, bool& updated);

}  // namespace vtex::pipelines::detail
