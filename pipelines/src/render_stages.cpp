// See render_stages.h.
#include "render_stages.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/render/compare.h>
#include <vtex/render/image.h>

#include "content_hash.h"
#include "tile_assembly.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <set>
#include <sstream>
#include <tuple>

namespace vtex::pipelines::detail {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// Every field of a render step, in the lines its keys begin with after the header or named as
// not in them: the structured binding stops compiling when RenderStep gains a field, until it is
// placed here. (`name` names the outputs; the scene and the texels enter by their content, in
// the keys' later lines; `tiles` in the tile's and the assembly's own lines.)
std::string renderParameters(const RenderStep& step) {
    [[maybe_unused]] const auto& [name, scene, texels, width, height, spp, lodBias, shading, hybrid, levelFit,
                                  approximations, renderer, mode, tiles] = step;
    std::ostringstream d;
    d << "render " << kRendererNames.name(renderer) << " " << render::kReferenceModeNames.name(mode) << "\nsize " << width
      << "x" << height << " spp " << spp << " lod_bias " << lodBias << " shading " << render::kShadingModeNames.name(shading)
      << " hybrid " << hybrid << " level_fit " << levelFit << "\napproximations "
      << renderOptions(step).approximations.key() << "\n";
    return d.str();
}

// The inputs' output hashes, one line each: what ties a stage's key to its inputs' content.
void describeInputs(std::ostream& d, const std::vector<Stage>& stages, const Stage& self) {
    for (std::size_t input : self.inputs)
        for (const auto& [role, hash] : stages[input].outputHashes) d << role << " " << hash << "\n";
}

// The image, its preview (when the stage has one: a tile has none) and its stats, all or none
// (commitAll).
void writeOutputs(const Stage& self, const render::Image& image, const std::string& stats) {
    AtomicOutputFile exr(self.outputs.at("image")), statsFile(self.outputs.at("stats"));
    std::optional<AtomicOutputFile> preview;
    render::writeExr(image, exr);
    if (self.outputs.count("preview")) render::writePng(image, preview.emplace(self.outputs.at("preview")));
    statsFile.stream() << stats;
    commitAll({&exr, preview ? &*preview : nullptr, &statsFile});
}

}  // namespace

namespace {

// What both renderers take from a step: the image and its sampling, and the rows a tile makes.
render::ImageOptions imageOptions(const RenderStep& step, std::pair<int, int> rows) {
    render::ImageOptions o;
    o.width = step.width;
    o.height = step.height;
    o.spp = step.spp;
    std::tie(o.rowBegin, o.rowEnd) = rows;
    return o;
}

}  // namespace

render::RenderOptions renderOptions(const RenderStep& step, std::pair<int, int> rows) {
    render::RenderOptions o;
    static_cast<render::ImageOptions&>(o) = imageOptions(step, rows);
    o.lodBias = step.lodBias;
    o.hybrid = step.hybrid;
    o.fitLevels = step.levelFit;
    if (step.approximations == Approximations::Exact) o.approximations = render::ApproximationBudget::exact();
    o.shading = step.shading;
    return o;
}

render::ReferenceOptions referenceOptions(const RenderStep& step, std::pair<int, int> rows) {
    render::ReferenceOptions o;
    static_cast<render::ImageOptions&>(o) = imageOptions(step, rows);
    o.mode = step.mode;
    return o;
}

render::Scene RenderWork::boundScene(const std::vector<Stage>& stages, const Stage& self) const {
    render::Scene scene = *mSpec.scene;
    std::size_t input = 0;
    for (const auto& [sceneTexel, texel] : mSpec.bindings) {
        render::TexelDef* found = &scene.texels[sceneTexelIndex(scene, sceneTexel)];
        found->volume = stages[self.inputs[input]].outputs.at("octree");
        found->source = stages[self.inputs[input + 1]].outputs.at("mesh");
        input += 2;
    }
    return scene;
}

std::string RenderWork::describe(const std::vector<Stage>& stages, const Stage& self) const {
    const RenderStep& step = mSpec.step;
    std::ostringstream d;
    d << mSpec.header << renderParameters(step) << "scene " << hashFile(step.scene) << "\n";
    const render::Scene scene = boundScene(stages, self);
    for (const auto& surface : scene.surfaces) d << "mesh " << hashFile(surface.mesh) << "\n";
    // The files of the texels the scene itself names, once each; bound texels are the
    // pipeline's artifacts, whose hashes the inputs give below.
    std::set<std::size_t> unbound;
    for (const auto& surface : scene.surfaces)
        if (surface.texel && std::none_of(mSpec.bindings.begin(), mSpec.bindings.end(), [&](const auto& b) {
                return b.first == scene.texels[*surface.texel].name;
            }))
            unbound.insert(*surface.texel);
    for (std::size_t t : unbound) {
        const render::TexelDef& texel = scene.texels[t];
        d << "texel " << t << " " << hashFile(texel.volume);
        if (step.renderer == Renderer::Reference && !texel.source.empty()) d << " source " << hashFile(texel.source);
        d << "\n";
    }
    describeInputs(d, stages, self);
    // An unsplit render's text is what it was before tiles: its cache stays valid.
    if (mTile >= 0) d << "tile " << mTile << " of " << step.tiles << "\n";
    return d.str();
}

Json RenderWork::run(const std::vector<Stage>& stages, const Stage& self) const {
    const RenderStep& step = mSpec.step;
    const render::Scene scene = boundScene(stages, self);
    const std::pair<int, int> rows = mTile >= 0 ? tileRows(mSpec.height(), step.tiles, mTile) : std::pair{0, 0};
    const bool reference = step.renderer == Renderer::Reference;
    const render::ReferenceOptions referenceSettings = referenceOptions(step, rows);
    const render::RenderOptions renderSettings = renderOptions(step, rows);
    std::string what = "rendering " + std::to_string(mSpec.width()) + "x" + std::to_string(mSpec.height());
    if (rows.second > 0) what += " rows " + std::to_string(rows.first) + " to " + std::to_string(rows.second);
    const auto held = mBudget.reserve(step.scene, what,
                                      reference ? render::estimateReferenceMemory(scene, referenceSettings)
                                                : render::estimateRenderMemory(scene, renderSettings));
    const render::RenderResult result = reference ? render::renderReference(scene, referenceSettings, *self.progress)
                                                  : render::renderScene(scene, renderSettings, *self.progress);
    const std::string stats = render::formatStatsJson(result.stats);
    writeOutputs(self, result.image, stats);
    return Json::parse(stats);
}

std::string AssemblyWork::describe(const std::vector<Stage>& stages, const Stage& self) const {
    std::ostringstream d;
    d << mSpec.header << renderParameters(mSpec.step) << "assemble " << self.inputs.size() << " tiles\n";
    describeInputs(d, stages, self);
    return d.str();
}

Json AssemblyWork::run(const std::vector<Stage>& stages, const Stage& self) const {
    const int width = mSpec.width(), height = mSpec.height();
    std::vector<fs::path> images, stats;
    for (std::size_t input : self.inputs) {
        images.push_back(stages[input].outputs.at("image"));
        stats.push_back(stages[input].outputs.at("stats"));
    }
    // The whole image and one tile at a time (RGBA floats, 16 bytes a pixel each), the PNG
    // encoder's copy and 16 MiB besides.
    const auto held = mBudget.reserve(mSpec.step.scene, "assembling " + std::to_string(width) + "x" + std::to_string(height),
                                      std::uint64_t(width) * std::uint64_t(height) * 38 + (std::uint64_t(16) << 20));
    const render::Image image = stackTiles(images, width, height);
    const Json merged = mergeTileStats(stats);
    writeOutputs(self, image, merged.dump(2) + "\n");
    return merged;
}

std::string CompareWork::describe(const std::vector<Stage>& stages, const Stage& self) const {
    [[maybe_unused]] const auto& [name, a, b] = mStep;  // a and b enter by their images' content
    return mHeader + "compare\nheatmap_scale truth_rms\n" + stages[self.inputs[0]].outputHashes.at("image") + "\n" +
           stages[self.inputs[1]].outputHashes.at("image") + "\n";
}

Json CompareWork::run(const std::vector<Stage>& stages, const Stage& self) const {
    const render::Image a = render::readExr(stages[self.inputs[0]].outputs.at("image"));
    const render::Image b = render::readExr(stages[self.inputs[1]].outputs.at("image"));
    if (a.width != b.width || a.height != b.height)
        throw InputError(stages[self.inputs[1]].outputs.at("image"), "size differs from render '" + mStep.a + "'");
    const render::ImageComparison m = render::compareImages(a, b);
    // One scale for every comparison against this truth (render::heatMapScale); a black truth
    // gets errorHeatMap's own fallback of 1, so that the report's bar is the map's.
    const double truthScale = render::heatMapScale(b), scale = truthScale > 0 ? truthScale : 1.0;
    render::writePng(render::errorHeatMap(a, b, scale), self.outputs.at("heatmap"));
    Json metrics = {{"a", mStep.a},      {"b", mStep.b},       {"rmse", m.rmse},
                    {"ssim", m.ssim},    {"worst_error", m.worstError}, {"heatmap_scale", scale},
                    {"psnr", std::isfinite(m.psnr) ? Json(m.psnr) : Json(nullptr)}};
    writeFileAtomically(self.outputs.at("metrics"), metrics.dump(2) + "\n");
    return metrics;
}

}  // namespace vtex::pipelines::detail
