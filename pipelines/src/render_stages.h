// The work of the stages a RenderStep and a CompareStep make (stage_graph.h): a render stage;
// for a render split into tiles (RenderStep::tiles), one tile stage per tile of rows and the
// render stage that assembles them (tile_assembly.h); a comparison of two renders.
#pragma once

#include "stage_graph.h"

#include <vtex/core/memory_budget.h>
#include <vtex/render/reference.h>
#include <vtex/render/renderer.h>
#include <vtex/render/scene.h>

#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace vtex::pipelines::detail {

/// The renderers' options a render step asks for, for the rows [rows.first, rows.second) of the
/// image (0/0: every row; ImageOptions::rowBegin).
render::RenderOptions renderOptions(const RenderStep& step, std::pair<int, int> rows = {0, 0});
render::ReferenceOptions referenceOptions(const RenderStep& step, std::pair<int, int> rows = {0, 0});

/// What a render and its tiles share: the step, its scene as loaded once when the graph was
/// built, the texels it binds that the pipeline builds (scene texel, pipeline texel), and the
/// keys' first line. A stage that renders has as inputs, binding by binding, the texel's build
/// and its source.
struct RenderSpec {
    RenderStep step;
    std::shared_ptr<const render::Scene> scene;
    std::vector<std::pair<std::string, std::string>> bindings;
    std::string header;
    int width() const { return step.width > 0 ? step.width : scene->camera.width; }
    int height() const { return step.height > 0 ? step.height : scene->camera.height; }
};

/// render/NAME, or tile/NAME.K (`tile` ≥ 0): renders the image, or tile K's rows of it
/// (tileRows), into the stage's "image" (EXR), "preview" (PNG, a render's) and "stats".
class RenderWork final : public StageWork {
public:
    RenderWork(RenderSpec spec, int tile, MemoryBudget& budget) : mSpec(std::move(spec)), mTile(tile), mBudget(budget) {}
    std::string describe(const std::vector<Stage>& stages, const Stage& self) const override;
    nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const override;

private:
    /// The scene as this stage sees it: bound texels point at its inputs' artifacts.
    render::Scene boundScene(const std::vector<Stage>& stages, const Stage& self) const;

    RenderSpec mSpec;
    int mTile;  ///< < 0: the whole image
    MemoryBudget& mBudget;
};

/// render/NAME of a tiled render: its tiles (the stage's inputs, in order) stacked into the image
/// and their stats merged, written all or none.
class AssemblyWork final : public StageWork {
public:
    AssemblyWork(RenderSpec spec, MemoryBudget& budget) : mSpec(std::move(spec)), mBudget(budget) {}
    std::string describe(const std::vector<Stage>& stages, const Stage& self) const override;
    nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const override;

private:
    RenderSpec mSpec;
    MemoryBudget& mBudget;
};

/// compare/NAME: render `a` (input 0) against the truth `b` (input 1), metrics and a heat map.
class CompareWork final : public StageWork {
public:
    CompareWork(CompareStep step, std::string header) : mStep(std::move(step)), mHeader(std::move(header)) {}
    std::string describe(const std::vector<Stage>& stages, const Stage& self) const override;
    nlohmann::json run(const std::vector<Stage>& stages, const Stage& self) const override;

private:
    CompareStep mStep;
    std::string mHeader;
};

}  // namespace vtex::pipelines::detail
