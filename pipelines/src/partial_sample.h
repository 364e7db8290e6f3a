// The sample stage of `vtex run` re-sampling only where its source changed (issue 13, "partial
// recompute"): the stage keeps, beside its volume, a copy of the mesh it sampled; when the
// source changes, the triangles that differ between that copy and the new mesh give the region
// (sampler::changedRegion) that sampler::updateRegion samples again. The build stage after it
// builds in full: resuming the earlier octree (`vtex build --update`) costs more than a full
// build (docs/formats.md, "Re-sampling a region"). Internal to vtex_pipelines.
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
};

/// `mesh` sampled with `options`: by updateRegion when the earlier run's manifest names
/// `earlier.parameters`, its volume and mesh copy have the content it recorded, and the change
/// allows a region smaller than half the volume; in full otherwise (no earlier run, another
/// resolution, a damaged or foreign file, a material, texture or mapping changed, a solid
/// interior). The result is the full sampling's either way.
SampleResult sampleOrUpdate(const ingest::TriangleMesh& mesh, const sampler::SampleOptions& options,
                            const EarlierSample& earlier, Progress& progress);

}  // namespace vtex::pipelines::detail
