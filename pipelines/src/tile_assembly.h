// A render split into tiles of rows (RenderStep::tiles): which rows each tile renders, and how
// the render's own stage puts the tiles' images and statistics back together.
#pragma once

#include <vtex/render/image.h>

#include <nlohmann/json.hpp>

#include <filesystem>
#include <utility>
#include <vector>

namespace vtex::pipelines::detail {

/// The rows [first, second) of tile k of `tiles` over `height` rows: [k·H/N, (k+1)·H/N), as
/// even as whole rows allow, every row in exactly one tile.
std::pair<int, int> tileRows(int height, int tiles, int k);

/// The tiles' EXRs (tile k the rows tileRows(height, N, k)) stacked into the width × height
/// image. Throws vtex::InputError naming the tile whose size is not its rows' (or whose AOVs
/// are not the others').
render::Image stackTiles(const std::vector<std::filesystem::path>& tiles, int width, int height);

/// One stats.json from the tiles' (docs/pipelines.md, "Tiles"): counters and times summed, the
/// level histogram summed level by level and the mean level taken from it, the rows gone,
/// "tiles": N and each tile's wall and load seconds ("tile_wall_seconds", "tile_load_seconds")
/// added; every other field must be the same in every tile (vtex::InputError naming the tile's
/// file and the field otherwise).
nlohmann::json mergeTileStats(const std::vector<std::filesystem::path>& stats);

}  // namespace vtex::pipelines::detail
