// See tile_assembly.h.
#include "tile_assembly.h"

#include <vtex/core/error.h>
#include <vtex/render/renderer.h>

#include <fstream>
#include <set>
#include <string>

namespace vtex::pipelines::detail {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

// The counters each tile counts for its own rows (their sum is the whole render's), and the
// times, which add up to the work the tiles did together, not to any one wall-clock time.
const std::set<std::string> kSummed = {"wall_seconds",           "load_seconds",   "cell_segments", "voxels_visited",
                                       "reflectance_evaluations", "vto_bytes_read", "mesh_segments"};
// Derived from the merged fields, or a tile's own: not carried over as they are.
const std::set<std::string> kNotCarried = {"rays", "level_histogram", "mean_level", "row_begin", "row_end"};

Json readStats(const fs::path& file) {
    std::ifstream in(file);
    if (!in) throw InputError(file, "cannot read the tile's statistics");
    try {
        return Json::parse(in);
    } catch (const Json::exception& e) {
        throw InputError(file, std::string("not a stats.json: ") + e.what());
    }
}

double number(const Json& stats, const std::string& key, const fs::path& file) {
    if (!stats.contains(key) || !stats[key].is_number()) throw InputError(file, "no number", key);
    return stats[key].get<double>();
}

}  // namespace

std::pair<int, int> tileRows(int height, int tiles, int k) {
    const auto row = [&](int i) { return int(std::int64_t(i) * height / tiles); };
    return {row(k), row(k + 1)};
}

render::Image stackTiles(const std::vector<fs::path>& tiles, int width, int height) {
    render::Image whole;
    for (std::size_t k = 0; k < tiles.size(); ++k) {
        const auto [begin, end] = tileRows(height, int(tiles.size()), int(k));
        render::Image tile = render::readExr(tiles[k]);
        if (tile.width != width || tile.height != end - begin)
            throw InputError(tiles[k], "is " + std::to_string(tile.width) + "x" + std::to_string(tile.height) +
                                           ", but tile " + std::to_string(k) + " of " + std::to_string(tiles.size()) +
                                           " holds rows " + std::to_string(begin) + " to " + std::to_string(end) +
                                           " of a " + std::to_string(width) + "x" + std::to_string(height) + " image");
        if (k == 0) whole = render::Image(width, height, tile.hasAovs());
        if (tile.hasAovs() != whole.hasAovs()) throw InputError(tiles[k], "its AOVs are not the first tile's");
        // Rows are contiguous in an Image (row-major): a tile is one block of the whole.
        const std::size_t at = std::size_t(begin) * std::size_t(width);
        std::copy(tile.rgba.begin(), tile.rgba.end(), whole.rgba.begin() + std::ptrdiff_t(4 * at));
        std::copy(tile.depth.begin(), tile.depth.end(), whole.depth.begin() + std::ptrdiff_t(at));
        std::copy(tile.level.begin(), tile.level.end(), whole.level.begin() + std::ptrdiff_t(at));
    }
    return whole;
}

Json mergeTileStats(const std::vector<fs::path>& files) {
    Json merged = Json::object();
    std::vector<double> histogram, wall, load;
    std::uint64_t primary = 0, shadow = 0;
    for (std::size_t k = 0; k < files.size(); ++k) {
        const Json tile = readStats(files[k]);
        for (const auto& [key, value] : tile.items()) {
            if (kSummed.count(key)) {
                if (value.is_number_integer()) merged[key] = merged.value(key, std::int64_t(0)) + value.get<std::int64_t>();
                else merged[key] = merged.value(key, 0.0) + number(tile, key, files[k]);
            } else if (kNotCarried.count(key) == 0) {
                // The same in every tile (the scene's, the options', what was measured at load).
                if (k == 0) merged[key] = value;
                else if (merged[key] != value) throw InputError(files[k], "differs from the first tile's", key);
            }
        }
        const Json rays = tile.value("rays", Json::object());
        primary += rays.value("primary", std::uint64_t(0));
        shadow += rays.value("shadow", std::uint64_t(0));
        const auto levels = tile.value("level_histogram", std::vector<double>());
        if (histogram.size() < levels.size()) histogram.resize(levels.size(), 0.0);
        for (std::size_t l = 0; l < levels.size(); ++l) histogram[l] += levels[l];
        wall.push_back(number(tile, "wall_seconds", files[k]));
        load.push_back(number(tile, "load_seconds", files[k]));
    }
    merged["rays"] = {{"primary", primary}, {"shadow", shadow}};
    merged["level_histogram"] = histogram;
    render::RenderStats levels;  // the mean level as a render computes it
    levels.levelHistogram = histogram;
    merged["mean_level"] = levels.meanLevel();
    merged["tiles"] = files.size();
    merged["tile_wall_seconds"] = wall;
    merged["tile_load_seconds"] = load;
    return merged;
}

}  // namespace vtex::pipelines::detail
