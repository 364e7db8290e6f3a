// See texel_stages.h.
#include "texel_stages.h"

#include <vtex/core/atomic_file.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/render/renderer.h>
#include <vtex/render/source_visibility.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include "content_hash.h"

#include <fstream>
#include <sstream>

namespace vtex::pipelines::detail {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

std::string readText(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// Every field of a source step, in its key or named as not in it: the structured binding stops
// compiling when SourceStep gains a field, until it is placed here.
std::string sourceParameters(const SourceStep& step) {
    [[maybe_unused]] const auto& [name, pattern, file, up, fitCell, seed, count, fluctuation, leanDegrees, variant] = step;
    // (`name` names the outputs, not their content.)
    std::ostringstream d;
    if (!pattern.empty())
        d << "pattern " << pattern << " seed " << seed << " count " << count << " fluctuation " << fluctuation << " lean "
          << leanDegrees << " variant " << variant << "\n";
    else
        d << "file " << hashFile(file) << " up " << (up ? up : '-') << " fit " << (fitCell ? "cell" : "keep") << "\n";
    return d.str();
}

}  // namespace

std::string SourceWork::describe(const std::vector<Stage>&, const Stage&) const {
    return mHeader + "source\n" + sourceParameters(mStep);
}

Json SourceWork::run(const std::vector<Stage>&, const Stage& self) const {
    ingest::TriangleMesh mesh;
    if (!mStep.pattern.empty()) {
        sampler::PatternOptions o;
        o.seed = mStep.seed;
        o.count = mStep.count;
        o.fluctuation = mStep.fluctuation;
        o.leanDegrees = mStep.leanDegrees;
        o.variant = mStep.variant;
        mesh = sampler::makePattern(mStep.pattern, o);
    } else {
        ingest::IngestOptions o;
        o.up = mStep.up;
        o.fitCell = mStep.fitCell;
        mesh = ingest::loadMesh(mStep.file, o);
    }
    ingest::writeMeshGlb(mesh, self.outputs.at("mesh"));
    return Json{{"triangles", mesh.triangles.size()}, {"closed", mesh.closed}};
}

// The texel's fields split between its two stages: sample (resolution, cyclic, solid) and build
// (filter, tolerance); `name` and `source` name the outputs and the input stage. A field added
// to TexelStep stops both from compiling until it is placed.
std::string sampleParameters(const TexelStep& step, std::uint32_t sampledResolution, bool cyclic, const std::string& header) {
    [[maybe_unused]] const auto& [name, source, resolution, stepCyclic, solid, filter, tolerance] = step;
    // (`resolution` and `cyclic` enter as resolved: the sampled resolution, the pattern's default.)
    std::ostringstream d;
    d << header << "sample\nresolution " << sampledResolution << " cyclic " << cyclic << " solid "
      << sampler::kSolidModeNames.name(solid) << "\n";
    return d.str();
}

std::string buildParameters(const TexelStep& step) {
    [[maybe_unused]] const auto& [name, source, resolution, cyclic, solid, filter, tolerance] = step;
    std::ostringstream d;
    d << "filter " << octree::kFilterRuleNames.name(filter) << " tolerance " << tolerance;
    return d.str();
}

std::string SampleWork::describe(const std::vector<Stage>& stages, const Stage& self) const {
    return mEarlier.parameters + "mesh " + stages[self.inputs[0]].outputHashes.at("mesh") + "\n";
}

Json SampleWork::run(const std::vector<Stage>& stages, const Stage& self) const {
    const fs::path meshFile = stages[self.inputs[0]].outputs.at("mesh");
    const std::string meshBytes = readText(meshFile);
    const ingest::TriangleMesh mesh = ingest::loadMesh(meshFile);
    sampler::SampleOptions o;
    o.resolution = mResolution;
    o.cyclic = mCyclic;
    o.solid = mSolid;
    const auto held = mBudget.reserve(meshFile, "sampling at " + std::to_string(mResolution) + "^3",
                                      sampler::estimateSampleMemory(mesh, o));
    Progress& quiet = *self.progress;
    // An edited source is re-sampled only where its triangles changed (not with --force).
    const SampleResult sampled =
        mForce ? SampleResult{sampler::sampleMesh(mesh, o, quiet), std::nullopt} : sampleOrUpdate(mesh, o, mEarlier, quiet);
    const octree::SparseVolume& volume = sampled.volume;
    // Both or neither: a copy of another mesh beside the volume would mislead the next run.
    AtomicOutputFile vtl(self.outputs.at("volume")), copy(self.outputs.at("sampled_mesh"));
    vtl.stream() << octree::serializeVtl(volume);
    copy.stream() << meshBytes;
    commitAll({&vtl, &copy});
    Json region = nullptr;
    if (sampled.region)
        region = {sampled.region->min[0], sampled.region->min[1], sampled.region->min[2],
                  sampled.region->max[0], sampled.region->max[1], sampled.region->max[2]};
    return Json{{"resolution", mResolution},
                {"maximum_resolution", mMaximumResolution},
                {"occupied_blocks", volume.blocks.size()},
                {"source_area", volume.info.sourceArea},
                {"fit_error_mean", volume.info.fitError.mean},
                {"parameters", mEarlier.parameters},
                {"updated_region", region}};
}

std::string BuildWork::describe(const std::vector<Stage>& stages, const Stage& self) const {
    const Stage& sample = stages[self.inputs[0]];
    // The source too: the stage measures each level against it (its details).
    return mHeader + "build\n" + mParameters + "\nvolume " + sample.outputHashes.at("volume") + "\nsource " +
           stages[sample.inputs[0]].outputHashes.at("mesh") + "\n";
}

Json BuildWork::run(const std::vector<Stage>& stages, const Stage& self) const {
    const Stage& sample = stages[self.inputs[0]];
    const fs::path sourceFile = stages[sample.inputs[0]].outputs.at("mesh");
    const fs::path volumeFile = sample.outputs.at("volume");
    const auto held = mBudget.reserve(volumeFile, "building its octree", octree::estimateBuildMemory(volumeFile));
    octree::SparseVolume volume = octree::readVtl(volumeFile);
    octree::BuildOptions o;
    o.rule = mFilter;
    o.tolerance = mTolerance;
    // In full after a partial re-sampling too: resuming the earlier octree costs more than a
    // full build (docs/formats.md, "Re-sampling a region").
    octree::Octree tree = octree::buildOctree(std::move(volume), o, *self.progress);
    // What the pipeline's renders (τ 1, default options) measure of the texel against its
    // source at load, stored in the octree as `vtex build --source` does (render::measureSource).
    const ingest::TriangleMesh source = ingest::loadMesh(sourceFile);
    tree.measures = render::measureSource(tree, source, 1.0, render::RenderOptions{}.hybridTolerance, sourceFile);
    octree::writeVto(tree, self.outputs.at("octree"));
    // Each level's fidelity to the source mesh (issue 13's measure; vtex inspect --source).
    const render::SourceFidelity fidelity = render::measureSourceFidelity(tree, source);
    Json levels = Json::array();
    for (std::uint32_t l = 0; l < tree.levelCount(); ++l)
        levels.push_back({{"level", l},
                          {"stored_nodes", tree.stats[l].storedNodes},
                          {"filter_error_mean", tree.stats[l].filterErrorMean},
                          {"chord_error", fidelity.chords[l].error()},
                          {"chord_error_fitted", l < fidelity.fitted.size() ? Json(fidelity.fitted[l].error()) : Json()},
                          {"level_fit_scale", l < fidelity.fitScale.size() ? Json(fidelity.fitScale[l]) : Json()},
                          {"beam_error_mean_abs", fidelity.beams[l].meanAbs},
                          {"beam_error_p95_abs", fidelity.beams[l].p95Abs}});
    return Json{{"stored_nodes", tree.storedNodes()}, {"compression", tree.compression()}, {"levels", levels},
                {"parameters", mParameters}};
}

}  // namespace vtex::pipelines::detail
