// The stage graph of a pipeline (stage_graph.h): which stages there are, what each reads and
// writes; their work is texel_stages.h's and render_stages.h's.
#include "stage_graph.h"

#include <vtex/core/error.h>
#include <vtex/core/version.h>
#include <vtex/render/level_bound.h>
#include <vtex/render/scene.h>
#include <vtex/sampler/patterns.h>

#include "render_stages.h"
#include "texel_stages.h"

#include <algorithm>
#include <bit>

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

// Builds the graph wave by wave; every stage's inputs come from an earlier wave.
struct GraphBuilder {
    const Pipeline& pipeline;
    fs::path root;
    bool force;
    MemoryBudget& budget;
    std::vector<Stage>& stages;
    std::vector<Omission>& leftOut;
    std::map<std::string, std::uint32_t> resolution;  // texel → sampled resolution; absent: not built
    std::map<std::string, std::shared_ptr<const render::Scene>> scenes;  // render → its scene
    std::map<std::string, std::size_t> sourceIndex, sampleIndex, buildIndex, renderIndex;
    std::map<std::string, std::vector<std::size_t>> tileIndex;  // render → its tile stages
    const std::string header = std::string("vtex ") + kVersion + "\n";

    bool isBuilt(const std::string& texel) const { return resolution.count(texel) > 0; }
    void fitResolutions();
    std::size_t add(Stage stage) {
        stages.push_back(std::move(stage));
        return stages.size() - 1;
    }
    void addSources();
    void addTexels();
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
    // Each render's scene, read once for the whole graph: its stages' keys and work use it.
    for (const RenderStep& step : pipeline.renders)
        scenes[step.name] = std::make_shared<const render::Scene>(render::loadScene(step.scene));
    if (pipeline.fitResolution && !pipeline.renders.empty()) {
        std::map<std::string, std::pair<int, std::string>> need;  // texel → (finest level, render)
        for (const RenderStep& step : pipeline.renders) {
            const render::Scene& scene = *scenes.at(step.name);
            const auto needs = render::finestUsefulLevels(scene, renderOptions(step));
            for (const auto& [sceneTexel, texel] : step.texels) {
                const auto& n = needs[sceneTexelIndex(scene, sceneTexel)];
                if (!n.used) continue;
                // A reference render reads only where the sampler placed the source (any level).
                const int level = step.renderer == Renderer::Reference ? 0 : n.unbounded ? 63 : n.finestLevel;
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
    for (const SourceStep& step : pipeline.sources) {
        Stage s{"source", step.name};
        s.outputs["mesh"] = root / "sources" / (step.name + ".glb");
        s.work = std::make_shared<SourceWork>(step, header);
        sourceIndex[step.name] = add(std::move(s));
    }
}

// All samples form one wave and all builds the next, so that texels run side by side.
void GraphBuilder::addTexels() {
    for (const TexelStep& step : pipeline.texels) {
        if (!isBuilt(step.name)) continue;
        const SourceStep& source = *std::find_if(pipeline.sources.begin(), pipeline.sources.end(),
                                                 [&](const SourceStep& s) { return s.name == step.source; });
        const bool cyclic = step.cyclic.value_or(!source.pattern.empty() && sampler::isCyclicPattern(source.pattern));
        Stage s{"sample", step.name};
        s.inputs = {sourceIndex.at(step.source)};
        s.outputs["volume"] = root / "samples" / (step.name + ".vtl");
        // The mesh the volume was sampled from, for the next run to find what changed.
        s.outputs["sampled_mesh"] = root / "samples" / (step.name + ".mesh.glb");
        const std::uint32_t sampled = resolution.at(step.name);
        EarlierSample earlier{manifestPath(s, root), s.outputs.at("volume"), s.outputs.at("sampled_mesh"),
                              sampleParameters(step, sampled, cyclic, header)};
        s.work = std::make_shared<SampleWork>(step, sampled, cyclic, std::move(earlier), force, budget);
        sampleIndex[step.name] = add(std::move(s));
    }
    for (const TexelStep& step : pipeline.texels) {
        if (!isBuilt(step.name)) continue;
        Stage b{"build", step.name};
        b.inputs = {sampleIndex.at(step.name)};
        b.outputs["octree"] = root / "builds" / (step.name + ".vto");
        b.work = std::make_shared<BuildWork>(step, buildParameters(step), header, budget);
        buildIndex[step.name] = add(std::move(b));
    }
}

RenderSpec GraphBuilder::renderSpec(const RenderStep& step) const {
    RenderSpec spec{step, scenes.at(step.name), {}, header};
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

// All tiles of all renders form one wave, before the renders that assemble them.
void GraphBuilder::addTiles() {
    for (const RenderStep& step : pipeline.renders) {
        if (step.tiles <= 1) continue;
        const RenderSpec spec = renderSpec(step);
        for (int k = 0; k < step.tiles; ++k) {
            Stage s{"tile", step.name + "." + std::to_string(k)};
            s.inputs = renderInputs(spec);
            s.outputs["image"] = root / "tiles" / (s.name + ".exr");
            s.outputs["stats"] = root / "tiles" / (s.name + ".stats.json");
            s.work = std::make_shared<RenderWork>(spec, k, budget);
            tileIndex[step.name].push_back(add(std::move(s)));
        }
    }
}

void GraphBuilder::addRenders() {
    for (const RenderStep& step : pipeline.renders) {
        const RenderSpec spec = renderSpec(step);
        Stage s{"render", step.name};
        s.outputs["image"] = root / "renders" / (step.name + ".exr");
        s.outputs["preview"] = root / "renders" / (step.name + ".png");
        s.outputs["stats"] = root / "renders" / (step.name + ".stats.json");
        if (step.tiles > 1) {  // the render assembles its tiles
            s.inputs = tileIndex.at(step.name);
            s.work = std::make_shared<AssemblyWork>(spec, budget);
        } else {
            s.inputs = renderInputs(spec);
            s.work = std::make_shared<RenderWork>(spec, -1, budget);
        }
        renderIndex[step.name] = add(std::move(s));
    }
}

void GraphBuilder::addCompares() {
    for (const CompareStep& step : pipeline.compares) {
        Stage s{"compare", step.name};
        s.inputs = {renderIndex.at(step.a), renderIndex.at(step.b)};
        s.outputs["metrics"] = root / "compares" / (step.name + ".json");
        s.outputs["heatmap"] = root / "compares" / (step.name + ".diff.png");
        s.work = std::make_shared<CompareWork>(step, header);
        add(std::move(s));
    }
}

}  // namespace

fs::path manifestPath(const Stage& stage, const fs::path& root) {
    return root / (stage.kind + "s") / (stage.name + ".manifest.json");
}

void buildStageGraph(const Pipeline& pipeline, const fs::path& root, bool force, MemoryBudget& budget,
                     std::vector<Stage>& stages, std::vector<Omission>& leftOut) {
    GraphBuilder graph{pipeline, root, force, budget, stages, leftOut, {}, {}, {}, {}, {}, {}, {}};
    graph.fitResolutions();
    graph.addSources();
    graph.addTexels();
    graph.addTiles();
    graph.addRenders();
    graph.addCompares();
    refuseSharedOutputs(stages, root, pipeline.file);
}

}  // namespace vtex::pipelines::detail
