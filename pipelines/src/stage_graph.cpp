// The stage graph of a pipeline (stage_graph.h): what each stage reads, hashes and writes.
#include "stage_graph.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/ingest/ingest.h>
#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/render/compare.h>
#include <vtex/render/level_bound.h>
#include <vtex/render/reference.h>
#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>
#include <vtex/render/source_visibility.h>
#include <vtex/sampler/patterns.h>
#include <vtex/sampler/sampler.h>

#include "content_hash.h"
#include "partial_sample.h"
#include "render_stages.h"

#include <algorithm>
#include <bit>
#include <cmath>
#include <fstream>
#include <set>
#include <sstream>

namespace vtex::pipelines::detail {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// Two stages that would write one file (a compare `c` and one named `c.manifest` both wrote
// compares/c.manifest.json, and the cache never settled): refused before anything runs, naming
// both stages and the file.
void refuseSharedOutputs(const std::vector<Stage>& stages, const fs::path& root, const fs::path& pipelineFile) {
    std::map<fs::path, std::string> writer;
    for (const Stage& stage : stages) {
        std::vector<fs::path> files{manifestPath(stage, root)};
        for (const auto& [role, file] : stage.outputs) files.push_back(file);
        for (const fs::path& file : files) {
            const std::string who = stage.kind + " '" + stage.name + "'";
            const auto [it, fresh] = writer.emplace(file.lexically_normal(), who);
            if (!fresh && it->second != who)
                throw InputError(pipelineFile, it->second + " and " + who + " would both write " + file.string());
        }
    }
}

std::string readText(const fs::path& file) {
    std::ifstream in(file, std::ios::binary);
    std::ostringstream s;
    s << in.rdbuf();
    return s.str();
}

// Builds the graph wave by wave; every stage's inputs come from an earlier wave.
struct GraphBuilder {
    const Pipeline& pipeline;
    fs::path root;
    bool force;
    MemoryBudget& budget;
    std::vector<Stage>& stages;
    std::vector<Omission>& leftOut;
    std::map<std::string, std::uint32_t> resolution;  // texel → sampled resolution; absent: not built
    std::map<std::string, std::size_t> sourceIndex, sampleIndex, buildIndex, renderIndex;
    std::map<std::string, std::vector<std::size_t>> tileIndex;  // render → its tile stages
    const std::string header = std::string("vtex ") + kVersion + "\n";

    bool isBuilt(const std::string& texel) const { return resolution.count(texel) > 0; }
    void fitResolutions();
    void addSources();
    void addSamples();
    void addBuilds();
    RenderSpec renderSpec(const RenderStep& step) const;
    std::vector<std::size_t> renderInputs(const RenderSpec& spec) const;
    void addTiles();
    void addRenders();
    void addCompares();
};

void GraphBuilder::fitResolutions() {
    // Leave out what the renders do not need: each texel is sampled to the finest level any
    // ray of any render can use (capped by its `resolution`), and texels no render uses are
    // not built at all.
    for (const TexelStep& step : pipeline.texels) resolution[step.name] = step.resolution;
    if (pipeline.fitResolution && !pipeline.renders.empty()) {
        std::map<std::string, std::pair<int, std::string>> need;  // texel → (finest level, render)
        for (const RenderStep& step : pipeline.renders) {
            const render::Scene scene = render::loadScene(step.scene);
            const auto needs = render::finestUsefulLevels(scene, renderOptions(step));
            for (const auto& [sceneTexel, texel] : step.texels) {
                const auto& n = needs[sceneTexelIndex(scene, sceneTexel)];
                if (!n.used) continue;
                // A reference render reads only where the sampler placed the source (any level).
                const int level = step.renderer == "reference" ? 0 : n.unbounded ? 63 : n.finestLevel;
                if (!need.count(texel) || level > need[texel].first) need[texel] = {level, step.name};
            }
        }
        for (const TexelStep& step : pipeline.texels) {
            const auto found = need.find(step.name);
            if (found == need.end()) {
                resolution.erase(step.name);
                leftOut.push_back({step.name, "not built: no surface of any render uses it"});
                continue;
            }
            const int cap = std::countr_zero(step.resolution);
            const int level = std::min(cap, found->second.first);
            resolution[step.name] = std::uint32_t(1) << level;
            if (level < cap)
                leftOut.push_back(
                    {step.name, "sampled at " + std::to_string(1u << level) + "³ instead of " +
                                    std::to_string(step.resolution) + "³: the finest level any ray of render '" +
                                    found->second.second + "' can use is " + std::to_string(found->second.first)});
        }
    }
}

void GraphBuilder::addSources() {
    const std::string header = this->header;
    for (const SourceStep& step : pipeline.sources) {
        Stage s{"source", step.name};
        s.outputs["mesh"] = root / "sources" / (step.name + ".glb");
        s.describe = [step, header] {
            std::ostringstream d;
            d << header << "source\n";
            if (!step.pattern.empty())
                d << "pattern " << step.pattern << " seed " << step.seed << " count " << step.count << " fluctuation "
                  << step.fluctuation << " lean " << step.leanDegrees << " variant " << step.variant << "\n";
            else
                d << "file " << hashFile(step.file) << " up " << (step.up ? step.up : '-') << " fit "
                  << (step.fitCell ? "cell" : "keep") << "\n";
            return d.str();
        };
        s.run = [step](Stage& self) {
            ingest::TriangleMesh mesh;
            if (!step.pattern.empty()) {
                sampler::PatternOptions o;
                o.seed = step.seed;
                o.count = step.count;
                o.fluctuation = step.fluctuation;
                o.leanDegrees = step.leanDegrees;
                o.variant = step.variant;
                mesh = sampler::makePattern(step.pattern, o);
            } else {
                ingest::IngestOptions o;
                o.up = step.up;
                o.fitCell = step.fitCell;
                mesh = ingest::loadMesh(step.file, o);
            }
            ingest::writeMeshGlb(mesh, self.outputs.at("mesh"));
            return Json{{"triangles", mesh.triangles.size()}, {"closed", mesh.closed}};
        };
        sourceIndex[step.name] = stages.size();
        stages.push_back(std::move(s));
    }
}

void GraphBuilder::addSamples() {
    std::vector<Stage>& stages = this->stages;  // the closures capture the vector, not the builder
    MemoryBudget& budget = this->budget;
    for (const TexelStep& step : pipeline.texels) {
        if (!isBuilt(step.name)) continue;
        const std::uint32_t sampledResolution = resolution.at(step.name);
        const SourceStep& source = *std::find_if(pipeline.sources.begin(), pipeline.sources.end(),
                                                 [&](const SourceStep& s) { return s.name == step.source; });
        const bool cyclic = step.cyclic.value_or(!source.pattern.empty() && sampler::isCyclicPattern(source.pattern));
        Stage sample{"sample", step.name};
        sample.inputs = {sourceIndex.at(step.source)};
        sample.outputs["volume"] = root / "samples" / (step.name + ".vtl");
        // The mesh the volume was sampled from, for the next run to find what changed.
        sample.outputs["sampled_mesh"] = root / "samples" / (step.name + ".mesh.glb");
        sampleIndex[step.name] = stages.size();
        stages.push_back(std::move(sample));
        Stage& s = stages.back();
        const std::size_t sourceStage = s.inputs[0];
        std::ostringstream parameters;
        parameters << header << "sample\nresolution " << sampledResolution << " cyclic " << cyclic << " solid " << step.solid
                   << "\n";
        s.describe = [&stages, sourceStage, parameters = parameters.str()] {
            return parameters + "mesh " + stages[sourceStage].outputHashes.at("mesh") + "\n";
        };
        const detail::EarlierSample earlier{manifestPath(s, root), s.outputs.at("volume"), s.outputs.at("sampled_mesh"),
                                            parameters.str()};
        s.run = [&stages, &budget, step, cyclic, sourceStage, sampledResolution, earlier, force = force](Stage& self) {
            const fs::path meshFile = stages[sourceStage].outputs.at("mesh");
            const std::string meshBytes = readText(meshFile);
            const ingest::TriangleMesh mesh = ingest::loadMesh(meshFile);
            sampler::SampleOptions o;
            o.resolution = sampledResolution;
            o.cyclic = cyclic;
            o.solid = step.solid == "on" ? sampler::SolidMode::On
                      : step.solid == "off" ? sampler::SolidMode::Off
                                            : sampler::SolidMode::Auto;
            const auto held = budget.reserve(meshFile, "sampling at " + std::to_string(sampledResolution) + "^3",
                                             sampler::estimateSampleMemory(mesh, o));
            Progress& quiet = *self.progress;
            // An edited source is re-sampled only where its triangles changed (not with --force).
            const detail::SampleResult sampled = force ? detail::SampleResult{sampler::sampleMesh(mesh, o, quiet), std::nullopt, {}}
                                                       : detail::sampleOrUpdate(mesh, o, earlier, quiet);
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
            return Json{{"resolution", sampledResolution},
                        {"maximum_resolution", step.resolution},
                        {"occupied_blocks", volume.blocks.size()},
                        {"source_area", volume.info.sourceArea},
                        {"fit_error_mean", volume.info.fitError.mean},
                        {"parameters", earlier.parameters},
                        {"updated_region", region},
                        {"updated_from", sampled.updatedFrom}};
        };
    }
}

void GraphBuilder::addBuilds() {
    std::vector<Stage>& stages = this->stages;  // the closures capture the vector, not the builder
    MemoryBudget& budget = this->budget;
    const std::string header = this->header;
    // All samples form one wave and all builds the next, so that texels run side by side.
    for (const TexelStep& step : pipeline.texels) {
        if (!isBuilt(step.name)) continue;
        Stage build{"build", step.name};
        build.inputs = {sampleIndex.at(step.name)};
        build.outputs["octree"] = root / "builds" / (step.name + ".vto");
        buildIndex[step.name] = stages.size();
        stages.push_back(std::move(build));
        Stage& b = stages.back();
        const std::size_t sampleStage = b.inputs[0];
        b.describe = [&stages, step, sampleStage, header] {
            std::ostringstream d;
            // The source too: the stage measures each level against it (its details).
            d << header << "build\nfilter " << step.filter << " tolerance " << step.tolerance << "\nvolume "
              << stages[sampleStage].outputHashes.at("volume") << "\nsource "
              << stages[stages[sampleStage].inputs[0]].outputHashes.at("mesh") << "\n";
            return d.str();
        };
        std::ostringstream buildParameters;
        buildParameters << "filter " << step.filter << " tolerance " << step.tolerance;
        const detail::EarlierBuild earlierBuild{manifestPath(b, root), b.outputs.at("octree"), buildParameters.str()};
        b.run = [&stages, &budget, step, sampleStage, earlierBuild](Stage& self) {
            const fs::path sourceFile = stages[stages[sampleStage].inputs[0]].outputs.at("mesh");
            const fs::path volumeFile = stages[sampleStage].outputs.at("volume");
            const auto held = budget.reserve(volumeFile, "building its octree", octree::estimateBuildMemory(volumeFile));
            octree::SparseVolume volume = octree::readVtl(volumeFile);
            octree::BuildOptions o;
            o.rule = *octree::parseFilterRule(step.filter);
            o.tolerance = step.tolerance;
            Progress& quiet = *self.progress;
            // After a partial re-sampling, only the region's ancestors are filtered again.
            const Stage& sample = stages[sampleStage];
            std::optional<octree::VoxelBox> region;
            std::string updatedFrom;
            // (cached or run: buildOrUpdate checks that the earlier build built the volume the
            // region was re-sampled from).
            if (!sample.record.detailsJson.empty()) {
                const Json d = Json::parse(sample.record.detailsJson);
                if (d.value("updated_region", Json()).is_array()) {
                    const auto r = d["updated_region"].get<std::vector<std::uint32_t>>();
                    region = octree::VoxelBox{{r.at(0), r.at(1), r.at(2)}, {r.at(3), r.at(4), r.at(5)}};
                    updatedFrom = d.value("updated_from", std::string());
                }
            }
            bool updated = false;
            const octree::Octree tree = detail::buildOrUpdate(std::move(volume), o, region, updatedFrom, earlierBuild, quiet, updated);
            octree::writeVto(tree, self.outputs.at("octree"));
            // Each level's fidelity to the source mesh (issue 13's measure; vtex inspect --source).
            const render::SourceFidelity fidelity = render::measureSourceFidelity(tree, ingest::loadMesh(sourceFile));
            Json levels = Json::array();
            for (std::uint32_t l = 0; l < tree.levelCount(); ++l)
                levels.push_back({{"level", l},
                                  {"stored_nodes", tree.stats[l].storedNodes},
                                  {"filter_error_mean", tree.stats[l].filterErrorMean},
                                  {"chord_error", fidelity.chords[l].error()},
                                  {"beam_error_mean_abs", fidelity.beams[l].meanAbs},
                                  {"beam_error_p95_abs", fidelity.beams[l].p95Abs}});
            return Json{{"stored_nodes", tree.storedNodes()}, {"compression", tree.compression()}, {"levels", levels},
                        {"parameters", earlierBuild.parameters}, {"volume", sample.outputHashes.at("volume")},
                        {"updated", updated}};
        };
    }
}

RenderSpec GraphBuilder::renderSpec(const RenderStep& step) const {
    RenderSpec spec{step, {}, header};
    // Bindings of texels that were left out name texels the scene does not use.
    for (const auto& binding : step.texels)
        if (isBuilt(binding.second)) spec.bindings.push_back(binding);
    return spec;
}

std::vector<std::size_t> GraphBuilder::renderInputs(const RenderSpec& spec) const {
    std::vector<std::size_t> inputs;
    for (const auto& [sceneTexel, texel] : spec.bindings) {
        inputs.push_back(buildIndex.at(texel));
        inputs.push_back(sourceIndex.at(std::find_if(pipeline.texels.begin(), pipeline.texels.end(),
                                                     [&](const TexelStep& t) { return t.name == texel; })
                                            ->source));
    }
    return inputs;
}

void GraphBuilder::addTiles() {
    std::vector<Stage>& stages = this->stages;  // the closures capture the vector, not the builder
    MemoryBudget& budget = this->budget;
    // All tiles of all renders form one wave, before the renders that assemble them.
    for (const RenderStep& step : pipeline.renders) {
        if (step.tiles <= 1) continue;
        const RenderSpec spec = renderSpec(step);
        for (int k = 0; k < step.tiles; ++k) {
            Stage s{"tile", step.name + "." + std::to_string(k)};
            s.inputs = renderInputs(spec);
            s.outputs["image"] = root / "tiles" / (s.name + ".exr");
            s.outputs["stats"] = root / "tiles" / (s.name + ".stats.json");
            const std::size_t self = stages.size();
            tileIndex[step.name].push_back(self);
            s.describe = [&stages, spec, self, k] {
                return describeRender(stages, stages[self], spec) + "tile " + std::to_string(k) + " of " +
                       std::to_string(spec.step.tiles) + "\n";
            };
            s.run = [&stages, &budget, spec, k](Stage& me) {
                return runRender(me, stages, budget, spec, renderTileRows(spec, boundScene(stages, me, spec), k));
            };
            stages.push_back(std::move(s));
        }
    }
}

void GraphBuilder::addRenders() {
    std::vector<Stage>& stages = this->stages;  // the closures capture the vector, not the builder
    MemoryBudget& budget = this->budget;
    for (const RenderStep& step : pipeline.renders) {
        const RenderSpec spec = renderSpec(step);
        Stage s{"render", step.name};
        s.outputs["image"] = root / "renders" / (step.name + ".exr");
        s.outputs["preview"] = root / "renders" / (step.name + ".png");
        s.outputs["stats"] = root / "renders" / (step.name + ".stats.json");
        const std::size_t self = stages.size();
        renderIndex[step.name] = self;
        if (step.tiles > 1) {  // the render assembles its tiles
            s.inputs = tileIndex.at(step.name);
            s.describe = [&stages, spec, self] { return describeAssembly(stages, stages[self], spec); };
            s.run = [&stages, &budget, spec](Stage& me) { return runAssembly(me, stages, budget, spec); };
        } else {
            s.inputs = renderInputs(spec);
            s.describe = [&stages, spec, self] { return describeRender(stages, stages[self], spec); };
            s.run = [&stages, &budget, spec](Stage& me) { return runRender(me, stages, budget, spec, {0, 0}); };
        }
        stages.push_back(std::move(s));
    }
}

void GraphBuilder::addCompares() {
    std::vector<Stage>& stages = this->stages;  // the closures capture the vector, not the builder
    const std::string header = this->header;
    for (const CompareStep& step : pipeline.compares) {
        Stage s{"compare", step.name};
        s.inputs = {renderIndex.at(step.a), renderIndex.at(step.b)};
        s.outputs["metrics"] = root / "compares" / (step.name + ".json");
        s.outputs["heatmap"] = root / "compares" / (step.name + ".diff.png");
        const std::size_t self = stages.size();
        stages.push_back(std::move(s));
        Stage& c = stages.back();
        c.describe = [&stages, self, header] {
            const Stage& me = stages[self];
            return header + "compare\nheatmap_scale truth_rms\n" + stages[me.inputs[0]].outputHashes.at("image") + "\n" +
                   stages[me.inputs[1]].outputHashes.at("image") + "\n";
        };
        c.run = [&stages, step](Stage& self) {
            const render::Image a = render::readExr(stages[self.inputs[0]].outputs.at("image"));
            const render::Image b = render::readExr(stages[self.inputs[1]].outputs.at("image"));
            if (a.width != b.width || a.height != b.height)
                throw InputError(stages[self.inputs[1]].outputs.at("image"), "size differs from render '" + step.a + "'");
            const render::ImageComparison m = render::compareImages(a, b);
            // One scale for every comparison against this truth (render::heatMapScale); a black
            // truth gets errorHeatMap's own fallback of 1, so that the report's bar is the map's.
            const double truthScale = render::heatMapScale(b), scale = truthScale > 0 ? truthScale : 1.0;
            render::writePng(render::errorHeatMap(a, b, scale), self.outputs.at("heatmap"));
            Json metrics = {{"a", step.a},       {"b", step.b},       {"rmse", m.rmse},
                            {"ssim", m.ssim},     {"worst_error", m.worstError}, {"heatmap_scale", scale},
                            {"psnr", std::isfinite(m.psnr) ? Json(m.psnr) : Json(nullptr)}};
            writeFileAtomically(self.outputs.at("metrics"), metrics.dump(2) + "\n");
            return metrics;
        };
    }
}

}  // namespace

fs::path manifestPath(const Stage& stage, const fs::path& root) {
    return root / (stage.kind + "s") / (stage.name + ".manifest.json");
}

void buildStageGraph(const Pipeline& pipeline, const fs::path& root, bool force, MemoryBudget& budget,
                     std::vector<Stage>& stages, std::vector<Omission>& leftOut) {
    GraphBuilder graph{pipeline, root, force, budget, stages, leftOut, {}, {}, {}, {}, {}, {}};
    graph.fitResolutions();
    graph.addSources();
    graph.addSamples();
    graph.addBuilds();
    graph.addTiles();
    graph.addRenders();
    graph.addCompares();
    refuseSharedOutputs(stages, root, pipeline.file);
}

}  // namespace vtex::pipelines::detail
