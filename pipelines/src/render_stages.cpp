// See render_stages.h.
#include "render_stages.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/version.h>
#include <vtex/render/image.h>

#include "content_hash.h"
#include "tile_assembly.h"

#include <algorithm>
#include <fstream>
#include <functional>
#include <optional>
#include <set>
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

// The render's own parameters, the lines its keys begin with after the header.
std::string renderParameters(const RenderStep& step) {
    std::ostringstream d;
    d << "render " << step.renderer << " " << step.mode << "\nsize " << step.width << "x" << step.height << " spp "
      << step.spp << " lod_bias " << step.lodBias << " shading " << step.shading << " hybrid " << step.hybrid
      << " level_fit " << step.levelFit << "\napproximations " << renderOptions(step).approximations.key() << "\n";
    return d.str();
}

int imageWidth(const RenderStep& step, const render::Scene& scene) { return step.width > 0 ? step.width : scene.camera.width; }
int imageHeight(const RenderStep& step, const render::Scene& scene) {
    return step.height > 0 ? step.height : scene.camera.height;
}

// The image, its preview (when the stage has one: a tile has none) and its stats, all or none
// (commitAll).
void writeOutputs(const Stage& self, const render::Image& image, const std::function<void(AtomicOutputFile&)>& writeStats) {
    AtomicOutputFile exr(self.outputs.at("image")), stats(self.outputs.at("stats"));
    std::optional<AtomicOutputFile> preview;
    render::writeExr(image, exr);
    if (self.outputs.count("preview")) render::writePng(image, preview.emplace(self.outputs.at("preview")));
    writeStats(stats);
    commitAll({&exr, preview ? &*preview : nullptr, &stats});
}

}  // namespace

render::RenderOptions renderOptions(const RenderStep& step) {
    render::RenderOptions o;
    o.width = step.width;
    o.height = step.height;
    o.spp = step.spp;
    o.lodBias = step.lodBias;
    o.hybrid = step.hybrid;
    o.fitLevels = step.levelFit;
    if (step.approximations == "exact") o.approximations = render::ApproximationBudget::exact();
    o.shading = step.shading == "reference" ? render::ShadingMode::Reference : render::ShadingMode::Fast;
    return o;
}

render::ReferenceOptions referenceOptions(const RenderStep& step) {
    render::ReferenceOptions o;
    o.width = step.width;
    o.height = step.height;
    o.spp = step.spp;
    o.mode = step.mode == "deformed" ? render::ReferenceMode::Deformed : render::ReferenceMode::Embedded;
    return o;
}

render::Scene boundScene(const std::vector<Stage>& stages, const Stage& self, const RenderSpec& spec) {
    render::Scene scene = render::loadScene(spec.step.scene);
    std::size_t input = 0;
    for (const auto& [sceneTexel, texel] : spec.bindings) {
        render::TexelDef* found = &scene.texels[sceneTexelIndex(scene, sceneTexel)];
        found->volume = stages[self.inputs[input]].outputs.at("octree");
        found->source = stages[self.inputs[input + 1]].outputs.at("mesh");
        input += 2;
    }
    return scene;
}

std::string describeRender(const std::vector<Stage>& stages, const Stage& self, const RenderSpec& spec) {
    const RenderStep& step = spec.step;
    std::ostringstream d;
    d << spec.header << renderParameters(step) << "scene " << hashFile(step.scene) << "\n";
    const render::Scene scene = boundScene(stages, self, spec);
    for (const auto& surface : scene.surfaces) d << "mesh " << hashFile(surface.mesh) << "\n";
    // The files of the texels the scene itself names, once each; bound texels are the
    // pipeline's artifacts, whose hashes the inputs give below.
    std::set<std::size_t> unbound;
    for (const auto& surface : scene.surfaces)
        if (surface.texel && std::none_of(spec.bindings.begin(), spec.bindings.end(), [&](const auto& b) {
                return b.first == scene.texels[*surface.texel].name;
            }))
            unbound.insert(*surface.texel);
    for (std::size_t t : unbound) {
        const render::TexelDef& texel = scene.texels[t];
        d << "texel " << t << " " << hashFile(texel.volume);
        if (step.renderer == "reference" && !texel.source.empty()) d << " source " << hashFile(texel.source);
        d << "\n";
    }
    for (std::size_t input : self.inputs)
        for (const auto& [role, hash] : stages[input].outputHashes) d << role << " " << hash << "\n";
    return d.str();
}

Json runRender(Stage& self, const std::vector<Stage>& stages, MemoryBudget& budget, const RenderSpec& spec,
               std::pair<int, int> rows) {
    const RenderStep& step = spec.step;
    Progress& quiet = *self.progress;
    const render::Scene scene = boundScene(stages, self, spec);
    const bool reference = step.renderer == "reference";
    render::ReferenceOptions referenceSettings = referenceOptions(step);
    render::RenderOptions renderSettings = renderOptions(step);
    std::tie(referenceSettings.rowBegin, referenceSettings.rowEnd) = rows;
    std::tie(renderSettings.rowBegin, renderSettings.rowEnd) = rows;
    std::string what = "rendering " + std::to_string(imageWidth(step, scene)) + "x" + std::to_string(imageHeight(step, scene));
    if (rows.second > 0) what += " rows " + std::to_string(rows.first) + " to " + std::to_string(rows.second);
    const auto held = budget.reserve(step.scene, what,
                                     reference ? render::estimateReferenceMemory(scene, referenceSettings)
                                               : render::estimateRenderMemory(scene, renderSettings));
    const render::RenderResult result = reference ? render::renderReference(scene, referenceSettings, quiet)
                                                  : render::renderScene(scene, renderSettings, quiet);
    writeOutputs(self, result.image, [&](AtomicOutputFile& stats) { render::writeStatsJson(result.stats, stats); });
    return Json::parse(readText(self.outputs.at("stats")));
}

std::pair<int, int> renderTileRows(const RenderSpec& spec, const render::Scene& scene, int k) {
    return tileRows(imageHeight(spec.step, scene), spec.step.tiles, k);
}

std::string describeAssembly(const std::vector<Stage>& stages, const Stage& self, const RenderSpec& spec) {
    std::ostringstream d;
    d << spec.header << renderParameters(spec.step) << "assemble " << self.inputs.size() << " tiles\n";
    for (std::size_t input : self.inputs)
        for (const auto& [role, hash] : stages[input].outputHashes) d << role << " " << hash << "\n";
    return d.str();
}

Json runAssembly(Stage& self, const std::vector<Stage>& stages, MemoryBudget& budget, const RenderSpec& spec) {
    const render::Scene scene = render::loadScene(spec.step.scene);  // for the image's size
    const int width = imageWidth(spec.step, scene), height = imageHeight(spec.step, scene);
    std::vector<fs::path> images, stats;
    for (std::size_t input : self.inputs) {
        images.push_back(stages[input].outputs.at("image"));
        stats.push_back(stages[input].outputs.at("stats"));
    }
    // The whole image and one tile at a time (RGBA floats, 16 bytes a pixel each), the PNG
    // encoder's copy and 16 MiB besides.
    const auto held = budget.reserve(spec.step.scene, "assembling " + std::to_string(width) + "x" + std::to_string(height),
                                     std::uint64_t(width) * std::uint64_t(height) * 38 + (std::uint64_t(16) << 20));
    const render::Image image = stackTiles(images, width, height);
    const Json merged = mergeTileStats(stats);
    writeOutputs(self, image, [&](AtomicOutputFile& out) { out.stream() << merged.dump(2) << "\n"; });
    return merged;
}

}  // namespace vtex::pipelines::detail
