// Renders split into tiles of rows (`tiles = N`, issue 18): N tile stages and the render stage
// that assembles them, whose image is the unsplit render's bit for bit; the tiles are cached, run
// alone and reported like any stage; the assembly refuses a tile of the wrong size and merges
// the tiles' statistics.
#include "pipeline_project.h"
#include "run_vtex.h"
#include "tile_assembly.h"

#include <vtex/core/error.h>
#include <vtex/pipelines/pipeline.h>
#include <vtex/render/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cstring>
#include <filesystem>

namespace fs = std::filesystem;
using Json = nlohmann::json;
using vtex::pipelines::RunOptions;
using vtex::pipelines::RunReport;
using Status = vtex::pipelines::StageRecord::Status;

namespace {

// The project's hill (48×36), rendered by the texel renderer whole and in 3 tiles, and by the
// reference renderer whole and in 5 tiles (rows 0, 7, 14, 21, 28, 36: none a multiple of 16).
fs::path makeTiledProject(const std::string& name) {
    const fs::path dir = vtex::test::makeProject(name);
    vtex::test::writeText(dir / "pipeline.toml", "[pipeline]\noutput = \"out\"\n" + vtex::test::kGrassTexel + R"(
[[render]]
name = "whole"
scene = "hill.toml"
texels = { cover = "grass" }

[[render]]
name = "split"
scene = "hill.toml"
texels = { cover = "grass" }
tiles = 3

[[render]]
name = "reference-whole"
scene = "hill.toml"
texels = { cover = "grass" }
renderer = "reference"
spp = 4

[[render]]
name = "reference-split"
scene = "hill.toml"
texels = { cover = "grass" }
renderer = "reference"
spp = 4
tiles = 5

[[compare]]
name = "split-vs-reference"
a = "split"
b = "reference-split"
)");
    return dir;
}

RunReport run(const fs::path& dir, const std::string& stage = "") {
    RunOptions options;
    options.stage = stage;
    return vtex::pipelines::runPipeline(vtex::pipelines::loadPipeline(dir / "pipeline.toml"), options);
}

Json readJson(const fs::path& file) { return Json::parse(vtex::test::readText(file)); }

bool sameFloats(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

// The tiled render's image, preview and stats against the unsplit one's.
void expectTheUnsplitRender(const fs::path& renders, const std::string& whole, const std::string& split, int tiles) {
    const vtex::render::Image a = vtex::render::readExr(renders / (whole + ".exr"));
    const vtex::render::Image b = vtex::render::readExr(renders / (split + ".exr"));
    EXPECT_EQ(a.width, 48);
    EXPECT_EQ(a.height, 36);
    EXPECT_EQ(b.width, a.width);
    EXPECT_EQ(b.height, a.height);
    EXPECT_TRUE(sameFloats(a.rgba, b.rgba)) << split;
    double alpha = 0;  // something is seen: equal images of nothing would prove nothing
    for (std::size_t i = 0; i < a.pixels(); ++i) alpha += a.rgba[4 * i + 3];
    EXPECT_GT(alpha, 0.2 * double(a.pixels()));
    // The writers are deterministic: the files are the same bytes.
    EXPECT_EQ(vtex::test::readText(renders / (whole + ".exr")), vtex::test::readText(renders / (split + ".exr")));
    EXPECT_EQ(vtex::test::readText(renders / (whole + ".png")), vtex::test::readText(renders / (split + ".png")));
    const Json sa = readJson(renders / (whole + ".stats.json")), sb = readJson(renders / (split + ".stats.json"));
    EXPECT_EQ(sb["tiles"], tiles);
    EXPECT_EQ(sb["width"], 48);
    EXPECT_EQ(sb["height"], 36);
    EXPECT_FALSE(sb.contains("row_begin"));
    EXPECT_FALSE(sa.contains("tiles"));
    // The counters are per pixel: the tiles' add up to the unsplit render's.
    EXPECT_EQ(sb["rays"], sa["rays"]);
    EXPECT_EQ(sb["cell_segments"], sa["cell_segments"]);
    ASSERT_EQ(sb["level_histogram"].size(), sa["level_histogram"].size());
    for (std::size_t l = 0; l < sa["level_histogram"].size(); ++l)
        EXPECT_NEAR(sb["level_histogram"][l].get<double>(), sa["level_histogram"][l].get<double>(), 1e-9);
    EXPECT_NEAR(sb["mean_level"].get<double>(), sa["mean_level"].get<double>(), 1e-9);
    ASSERT_EQ(sb["tile_wall_seconds"].size(), std::size_t(tiles));
    double wall = 0;
    for (const Json& s : sb["tile_wall_seconds"]) wall += s.get<double>();
    EXPECT_DOUBLE_EQ(sb["wall_seconds"].get<double>(), wall);
    for (const char* same : {"renderer", "spp", "faces", "cells", "threads"}) EXPECT_EQ(sb[same], sa[same]) << same;
}

}  // namespace

TEST(Tiles, ATiledRenderIsTheUnsplitRenderBitForBit) {
    const fs::path dir = makeTiledProject("tiles");
    const RunReport first = run(dir);
    ASSERT_TRUE(first.succeeded());
    // source, sample, build, 3 + 5 tiles, 4 renders, 1 compare; the tiles before the renders.
    ASSERT_EQ(first.stages.size(), 16u);
    for (std::size_t i = 0; i < first.stages.size(); ++i) {
        const auto& s = first.stages[i];
        EXPECT_EQ(s.status, Status::Ran) << s.kind << " " << s.name << ": " << s.message;
        EXPECT_EQ(s.kind, i < 3 ? (i == 0 ? "source" : i == 1 ? "sample" : "build")
                          : i < 11 ? "tile" : i < 15 ? "render" : "compare") << i;
    }
    EXPECT_EQ(first.stages[3].name, "split.0");
    EXPECT_EQ(first.stages[10].name, "reference-split.4");
    const fs::path out = dir / "out";
    expectTheUnsplitRender(out / "renders", "whole", "split", 3);
    expectTheUnsplitRender(out / "renders", "reference-whole", "reference-split", 5);
    // Each tile is its rows of the image, with its manifest beside it; its stats say which rows.
    const vtex::render::Image tile = vtex::render::readExr(out / "tiles/reference-split.1.exr");
    EXPECT_EQ(tile.height, 7);
    EXPECT_TRUE(fs::exists(out / "tiles/reference-split.1.manifest.json"));
    const Json tileStats = readJson(out / "tiles/reference-split.1.stats.json");
    EXPECT_EQ(tileStats["row_begin"], 7);
    EXPECT_EQ(tileStats["row_end"], 14);
    EXPECT_EQ(tileStats["height"], 36);

    // The report: the tiles as stages that ran, the assembled render in the error-against-time
    // table with the tiles' summed time.
    const Json report = readJson(out / "report.json");
    int tiles = 0;
    for (const Json& s : report["stages"])
        if (s["kind"] == "tile") tiles += s["status"] == "ran";
    EXPECT_EQ(tiles, 8);
    ASSERT_EQ(report["error_against_time"].size(), 1u);
    const Json& row = report["error_against_time"][0]["rows"][0];
    EXPECT_EQ(row["render"], "split");
    const Json split = readJson(out / "renders/split.stats.json");
    EXPECT_DOUBLE_EQ(row["seconds"].get<double>(), split["wall_seconds"].get<double>() + split["load_seconds"].get<double>());
    EXPECT_NE(vtex::test::readText(out / "report.html").find("split.2"), std::string::npos);

    const RunReport second = run(dir);
    for (const auto& s : second.stages) EXPECT_EQ(s.status, Status::Cached) << s.kind << " " << s.name;
}

// A tile alone (what a cluster job runs) makes the bytes it makes in a whole run. The render
// then assembles again (the tile's stats, its timings, are new: the merged stats follow them),
// into the same image, so that what compares it stays cached.
TEST(Tiles, ATileRunsAloneFromTheCache) {
    const fs::path dir = makeTiledProject("tiles_alone");
    ASSERT_TRUE(run(dir).succeeded());
    const fs::path tile = dir / "out/tiles/split.1.exr", image = dir / "out/renders/split.exr";
    const std::string bytes = vtex::test::readText(tile), assembled = vtex::test::readText(image);
    fs::remove(tile);
    const auto alone = vtex::test::runVtex({"run", (dir / "pipeline.toml").string(), "--stage", "tile/split.1"});
    ASSERT_EQ(alone.exitStatus, 0) << alone.err;
    EXPECT_EQ(vtex::test::readText(tile), bytes);
    EXPECT_EQ(run(dir, "tile/split.1").stages.at(0).status, Status::Cached);
    EXPECT_EQ(run(dir, "render/split").stages.at(0).status, Status::Ran);
    EXPECT_EQ(vtex::test::readText(image), assembled);
    const RunReport after = run(dir);
    for (const auto& s : after.stages) EXPECT_EQ(s.status, Status::Cached) << s.kind << " " << s.name;
}

TEST(Tiles, RowsAreSplitEvenlyAndEveryRowOnce) {
    for (const auto& [height, tiles] : {std::pair{36, 5}, {36, 36}, {7, 3}, {16384, 256}, {1, 1}}) {
        int next = 0, least = height, most = 0;
        for (int k = 0; k < tiles; ++k) {
            const auto [begin, end] = vtex::pipelines::detail::tileRows(height, tiles, k);
            EXPECT_EQ(begin, next);
            least = std::min(least, end - begin);
            most = std::max(most, end - begin);
            next = end;
        }
        EXPECT_EQ(next, height);
        EXPECT_LE(most - least, 1) << height << " rows in " << tiles;
        EXPECT_GE(least, 1);
    }
}

TEST(Tiles, TheAssemblyRefusesATileOfTheWrongSizeNamingIt) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "pipelines" / "tiles_wrong";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const std::vector<fs::path> files = {dir / "t.0.exr", dir / "t.1.exr"};
    vtex::render::writeExr(vtex::render::Image(8, 3, false), files[0]);
    vtex::render::writeExr(vtex::render::Image(8, 3, false), files[1]);
    EXPECT_EQ(vtex::pipelines::detail::stackTiles(files, 8, 6).height, 6);
    for (const auto& [width, height] : {std::pair{8, 7}, {9, 6}, {8, 5}}) {
        try {
            vtex::pipelines::detail::stackTiles(files, width, height);
            ADD_FAILURE() << "stacked 8x3 tiles into " << width << "x" << height;
        } catch (const vtex::InputError& e) {
            EXPECT_EQ(e.file().filename(), height == 7 ? "t.1.exr" : "t.0.exr") << e.what();
        }
    }
}

TEST(Tiles, MergedStatsSumCountersAndRefuseTilesThatDisagree) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "pipelines" / "tiles_stats";
    fs::remove_all(dir);
    fs::create_directories(dir);
    const auto write = [&](const std::string& name, const Json& j) {
        vtex::test::writeText(dir / name, j.dump());
        return dir / name;
    };
    const Json a = {{"renderer", "texel"}, {"width", 8}, {"height", 6}, {"row_begin", 0}, {"row_end", 3},
                    {"wall_seconds", 1.5}, {"load_seconds", 0.25}, {"rays", {{"primary", 10}, {"shadow", 4}}},
                    {"voxels_visited", 7}, {"level_histogram", {1.0, 2.0}}, {"mean_level", 0.5}};
    Json b = a;
    b["row_begin"] = 3;
    b["row_end"] = 6;
    b["wall_seconds"] = 2.0;
    b["rays"]["primary"] = 20;
    b["level_histogram"] = {0.0, 1.0, 3.0};
    const Json merged = vtex::pipelines::detail::mergeTileStats({write("a.json", a), write("b.json", b)});
    EXPECT_EQ(merged["wall_seconds"], 3.5);
    EXPECT_EQ(merged["load_seconds"], 0.5);
    EXPECT_EQ(merged["rays"]["primary"], 30);
    EXPECT_EQ(merged["rays"]["shadow"], 8);
    EXPECT_EQ(merged["voxels_visited"], 14);
    EXPECT_EQ(merged["level_histogram"], Json({1.0, 3.0, 3.0}));
    EXPECT_DOUBLE_EQ(merged["mean_level"].get<double>(), (3.0 + 2 * 3.0) / 7.0);
    EXPECT_EQ(merged["tiles"], 2);
    EXPECT_EQ(merged["tile_wall_seconds"], Json({1.5, 2.0}));
    EXPECT_EQ(merged["height"], 6);
    EXPECT_FALSE(merged.contains("row_begin"));
    b["renderer"] = "reference-embedded";
    try {
        vtex::pipelines::detail::mergeTileStats({write("a.json", a), write("b.json", b)});
        ADD_FAILURE() << "merged tiles of two renderers";
    } catch (const vtex::InputError& e) {
        EXPECT_EQ(e.file().filename(), "b.json");
        EXPECT_EQ(e.location(), "renderer");
    }
}

TEST(Tiles, TheTilesKeyIsChecked) {
    const fs::path dir = makeTiledProject("tiles_key");
    std::string text = vtex::test::readText(dir / "pipeline.toml");
    text.replace(text.find("tiles = 3"), 9, "tiles = 37");  // the hill is 36 rows
    vtex::test::writeText(dir / "pipeline.toml", text);
    const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("render[1].tiles"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("36 rows"), std::string::npos) << r.err;
    text.replace(text.find("tiles = 37"), 10, "tiles = 0");
    vtex::test::writeText(dir / "pipeline.toml", text);
    EXPECT_EQ(vtex::test::runVtex({"run", (dir / "pipeline.toml").string()}).exitStatus, 3);
}
