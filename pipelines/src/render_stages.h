// The work of the stages a RenderStep makes (stage_graph.cpp builds them): a render stage, or,
// for a render split into tiles (RenderStep::tiles), one tile stage per tile of rows and the
// render stage that assembles them (tile_assembly.h).
#pragma once

#include "stage_graph.h"

#include <vtex/render/reference.h>
#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

#include <nlohmann/json.hpp>

#include <string>
#include <utility>
#include <vector>

namespace vtex::pipelines::detail {

render::RenderOptions renderOptions(const RenderStep& step);
render::ReferenceOptions referenceOptions(const RenderStep& step);

/// What a render and its tiles share: the step, the texels it binds that the pipeline builds
/// (scene texel, pipeline texel), and the cache keys' first line. A stage that renders has as
/// inputs, binding by binding, the texel's build and its source.
struct RenderSpec {
    RenderStep step;
    std::vector<std::pair<std::string, std::string>> bindings;
    std::string header;
};

/// The scene as the rendering stage `self` sees it: bound texels point at its inputs' artifacts.
render::Scene boundScene(const std::vector<Stage>& stages, const Stage& self, const RenderSpec& spec);

/// The canonical text of a render's parameters and inputs, as a rendering stage's key hashes it
/// (an unsplit render's is what it was before tiles: its cache stays valid).
std::string describeRender(const std::vector<Stage>& stages, const Stage& self, const RenderSpec& spec);

/// Renders the rows [rows.first, rows.second) of the image (0/0: all) and writes the stage's
/// "image" (EXR), "preview" (PNG, when it has one) and "stats", all or none. Returns the stats.
nlohmann::json runRender(Stage& self, const std::vector<Stage>& stages, MemoryBudget& budget, const RenderSpec& spec,
                         std::pair<int, int> rows);

/// The rows tile k of a tiled render renders (tileRows of the image's height).
std::pair<int, int> renderTileRows(const RenderSpec& spec, const render::Scene& scene, int k);

/// The assembling stage's key text: the render's parameters and its tiles' output hashes.
std::string describeAssembly(const std::vector<Stage>& stages, const Stage& self, const RenderSpec& spec);

/// Stacks the tiles (the stage's inputs, in order) into the image and merges their stats
/// (tile_assembly.h), writing the stage's image, preview and stats all or none. Returns the stats.
nlohmann::json runAssembly(Stage& self, const std::vector<Stage>& stages, MemoryBudget& budget, const RenderSpec& spec);

}  // namespace vtex::pipelines::detail
