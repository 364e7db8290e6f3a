// `vtex render` end to end: files written, exit statuses, errors naming the file and key.
#include "fixtures.h"
#include "run_vtex.h"

#include <gtest/gtest.h>

#include <fstream>

using namespace vtex::render;
using vtex::test::runVtex;
namespace fs = std::filesystem;

namespace {

// A scene of two patches carrying a texel of 2^levels voxels a side: stripes of spheres in the
// bottom 11/16 of its height.
fs::path makeSceneDir(const std::string& name, const std::string& cameraExtra = "", int levels = 4) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "cli" / name;
    fs::remove_all(dir);
    fs::create_directories(dir / "meshes");
    std::ofstream(dir / "meshes" / "plane.obj") << "v 0 0 0\nv 2 0 0\nv 2 2 0\nv 0 2 0\nv 2 0 0.5\nv 3 0 0.5\nv 3 2 0.5\nv 2 2 0.5\nf 1 2 3 4\nf 5 6 7 8\n";
    const int n = 1 << levels;
    const auto tree = test::makeOctree(levels, [n](int x, int y, int z) -> std::optional<vtex::octree::VoxelData> {
        if ((x + y) % 3 != 0 || z * 16 > 10 * n) return std::nullopt;
        return test::sphereVoxel(40, {0.2f, 0.7f, 0.2f});
    }, true);
    vtex::octree::writeVto(*tree, dir / "t.vto");
    std::ofstream(dir / "scene.toml") << "[camera]\nposition = [1, -3, 2.5]\nlook_at = [1.2, 1, 0]\nwidth = 40\nheight = 30\n"
                                      << cameraExtra
                                      << "[[light]]\ntype = \"directional\"\ndirection = [-1, 0.5, -1]\ncolor = [3, 3, 3]\n"
                                         "[[texel]]\nname = \"t\"\nvolume = \"t.vto\"\n"
                                         "[[surface]]\nmesh = \"meshes/plane.obj\"\ntexel = \"t\"\nheight = 0.4\nrepeat = [2, 2]\n";
    return dir;
}

}  // namespace

TEST(RenderCli, WritesExrPngAndStats) {
    const fs::path dir = makeSceneDir("ok");
    const auto r = runVtex({"render", (dir / "scene.toml").string(), "-o", (dir / "img.exr").string(), "--png",
                            (dir / "img.png").string(), "--stats", (dir / "stats.json").string(), "--aov",
                            "--threads", "2", "--spp", "4", "--lod-bias", "0.5"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_TRUE(r.out.empty());
    const Image image = readExr(dir / "img.exr");
    EXPECT_EQ(image.width, 40);
    EXPECT_EQ(image.height, 30);
    EXPECT_TRUE(image.hasAovs());
    double sum = 0;
    for (std::size_t i = 0; i < image.pixels(); ++i) sum += image.rgba[4 * i + 3];
    EXPECT_GT(sum, 0.2 * double(image.pixels()));
    EXPECT_GT(fs::file_size(dir / "img.png"), 100u);
    const std::string stats = vtex::test::readText(dir / "stats.json");
    for (const char* key : {"wall_seconds", "threads", "primary", "shadow", "voxels_visited", "level_histogram"})
        EXPECT_NE(stats.find(key), std::string::npos) << key;
    // --width/--height override the camera.
    const auto small = runVtex({"render", (dir / "scene.toml").string(), "-o", (dir / "small.exr").string(),
                                "--width", "8", "--height", "6", "--quiet"});
    ASSERT_EQ(small.exitStatus, 0) << small.err;
    EXPECT_EQ(readExr(dir / "small.exr").width, 8);
}

TEST(RenderCli, BadInputExitsThreeNamingFileAndKey) {
    const fs::path dir = makeSceneDir("bad", "fov_y = \"wide\"\n");
    const auto r = runVtex({"render", (dir / "scene.toml").string(), "-o", (dir / "img.exr").string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("scene.toml"), std::string::npos) << r.err;
    EXPECT_NE(r.err.find("camera.fov_y"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(dir / "img.exr"));

    const fs::path unknown = makeSceneDir("unknown", "focal = 3\n");
    const auto w = runVtex({"render", (unknown / "scene.toml").string(), "-o", (unknown / "img.exr").string()});
    EXPECT_EQ(w.exitStatus, 0) << w.err;
    EXPECT_NE(w.err.find("warning"), std::string::npos);
    EXPECT_NE(w.err.find("camera.focal"), std::string::npos);

    // A corrupted octree is refused with exit 3, naming it.
    const fs::path corrupt = makeSceneDir("corrupt");
    std::ofstream(corrupt / "t.vto", std::ios::binary | std::ios::trunc) << "not an octree";
    const auto c = runVtex({"render", (corrupt / "scene.toml").string(), "-o", (corrupt / "img.exr").string()});
    EXPECT_EQ(c.exitStatus, 3);
    EXPECT_NE(c.err.find("t.vto"), std::string::npos) << c.err;
    // Every file the scene names is reported with the scene file and the key that named it
    // (issue 16): the octree above, a missing mesh, a missing or broken source, for both renderers.
    EXPECT_NE(c.err.find("scene.toml: texel[0].volume: "), std::string::npos) << c.err;
    const fs::path files = makeSceneDir("files");
    std::string text = vtex::test::readText(files / "scene.toml");
    text.replace(text.find("meshes/plane.obj"), 16, "meshes/gone.obj");
    std::ofstream(files / "scene.toml", std::ios::trunc) << text;
    const auto mesh = runVtex({"render", (files / "scene.toml").string(), "-o", (files / "img.exr").string()});
    EXPECT_EQ(mesh.exitStatus, 3);
    EXPECT_NE(mesh.err.find("scene.toml: surface[0].mesh: "), std::string::npos) << mesh.err;
    EXPECT_NE(mesh.err.find("gone.obj"), std::string::npos) << mesh.err;
    const fs::path sources = makeSceneDir("sources");
    text = vtex::test::readText(sources / "scene.toml");
    text.replace(text.find("volume = \"t.vto\""), 16, "volume = \"t.vto\"\nsource = \"leaves.glb\"");
    std::ofstream(sources / "scene.toml", std::ios::trunc) << text;
    std::ofstream(sources / "leaves.glb") << "glTF but not really";
    for (const std::string command : {"render", "reference"}) {
        const auto r2 = runVtex({command, (sources / "scene.toml").string(), "-o", (sources / "img.exr").string()});
        EXPECT_EQ(r2.exitStatus, 3) << command;
        EXPECT_NE(r2.err.find("scene.toml: texel[0].source: "), std::string::npos) << command << ": " << r2.err;
        EXPECT_NE(r2.err.find("leaves.glb"), std::string::npos) << r2.err;
    }

    const auto missing = runVtex({"render", (dir / "nope.toml").string(), "-o", (dir / "img.exr").string()});
    EXPECT_EQ(missing.exitStatus, 3);
    const auto usage = runVtex({"render", (unknown / "scene.toml").string(), "-o", (dir / "img.exr").string(), "--shading", "magic"});
    EXPECT_EQ(usage.exitStatus, 2);
}

TEST(ReferenceCli, BothModesWriteTheirFilesAndMissingSourcesExitThree) {
    const fs::path dir = makeSceneDir("reference");
    // A texel renders without `source =`; the reference renderer needs it.
    const auto missing = runVtex({"reference", (dir / "scene.toml").string(), "-o", (dir / "truth.exr").string()});
    EXPECT_EQ(missing.exitStatus, 3);
    EXPECT_NE(missing.err.find("scene.toml"), std::string::npos) << missing.err;
    EXPECT_NE(missing.err.find("texel.source"), std::string::npos) << missing.err;
    EXPECT_FALSE(fs::exists(dir / "truth.exr"));

    std::ofstream(dir / "leaves.obj") << "v 0.1 0.1 0.1\nv 0.9 0.2 0.3\nv 0.5 0.8 0.9\nv 0.2 0.7 0.2\nf 1 2 3\nf 1 3 4\n";
    std::string scene = vtex::test::readText(dir / "scene.toml");
    scene.replace(scene.find("volume = \"t.vto\""), 16, "volume = \"t.vto\"\nsource = \"leaves.obj\"");
    std::ofstream(dir / "scene.toml", std::ios::trunc) << scene;
    for (const std::string mode : {"embedded", "deformed"}) {
        const fs::path exr = dir / (mode + ".exr");
        const auto r = runVtex({"reference", (dir / "scene.toml").string(), "-o", exr.string(), "--png",
                                (dir / (mode + ".png")).string(), "--stats", (dir / (mode + ".json")).string(),
                                "--spp", "4", "--mode", mode, "--quiet"});
        ASSERT_EQ(r.exitStatus, 0) << r.err;
        const Image image = readExr(exr);
        EXPECT_EQ(image.width, 40);
        EXPECT_TRUE(fs::exists(dir / (mode + ".png")));
        const std::string stats = vtex::test::readText(dir / (mode + ".json"));
        EXPECT_NE(stats.find("\"reference-" + mode + "\""), std::string::npos) << stats;
        EXPECT_NE(stats.find("reference_triangles"), std::string::npos) << stats;
    }
    // Over the memory limit: refused before anything is built or written (the deformed
    // triangles' own refusal: Reference.DeformedSceneOverTheMemoryLimitIsRefused).
    const auto big = runVtex({"reference", (dir / "scene.toml").string(), "-o", (dir / "big.exr").string(), "--mode",
                              "deformed", "--max-memory", "1KiB"});
    EXPECT_EQ(big.exitStatus, 3) << big.err;
    EXPECT_NE(big.err.find("needs about"), std::string::npos) << big.err;
    EXPECT_FALSE(fs::exists(dir / "big.exr"));
}

// Floating flags that are not finite numbers are bad usage naming the flag (exit 2), for every
// command that has one: CLI11's ranges let NaN through (issue 14, item 7).
TEST(RenderCli, FlagsThatAreNotFiniteNumbersAreRefusedNamingTheFlag) {
    const fs::path dir = makeSceneDir("finite");
    const std::string scene = (dir / "scene.toml").string(), out = (dir / "x.exr").string();
    const std::vector<std::vector<std::string>> commands = {
        {"render", scene, "-o", out, "--lod-bias"},     {"render", scene, "-o", out, "--shadow-refresh"},
        {"reference", scene, "-o", out, "--tolerance"},
        {"build", "in.vtl", "-o", "x.vto", "--tolerance"}, {"sample", "in.glb", "-o", "x.vtl", "--solid-density"},
        {"pattern", "grass", "-o", "x.glb", "--fluctuation"}, {"pattern", "grass", "-o", "x.glb", "--lean"},
        {"ingest", "in.obj", "-o", "x.glb", "--weld-tolerance"}, {"demo", "-o", "d", "--scale"}};
    for (const auto& command : commands)
        for (const std::string value : {"nan", "inf", "-inf", "1e999", "0.5x"}) {
            std::vector<std::string> args = command;
            args.push_back(value);
            const auto r = runVtex(args);
            EXPECT_EQ(r.exitStatus, 2) << args[0] << " " << command.back() << " " << value << ": " << r.err;
            EXPECT_NE(r.err.find(command.back()), std::string::npos) << r.err;
        }
    EXPECT_FALSE(fs::exists(out));
}

namespace {

// The offset and size of section `tag` of a vtex container, from its table (docs/formats.md:
// a 24-byte header, then 32 bytes a section: tag, reserved, offset, size, checksum).
std::pair<std::uint64_t, std::uint64_t> sectionSpan(const std::string& bytes, const std::string& tag) {
    const auto u64 = [&](std::size_t at) {
        std::uint64_t v = 0;
        for (int i = 0; i < 8; ++i) v |= std::uint64_t(std::uint8_t(bytes[at + std::size_t(i)])) << (8 * i);
        return v;
    };
    const std::uint32_t count = std::uint32_t(u64(8) >> 32);
    for (std::uint32_t i = 0; i < count; ++i) {
        const std::size_t entry = 24 + 32 * std::size_t(i);
        if (bytes.compare(entry, 4, tag) == 0) return {u64(entry + 8), u64(entry + 16)};
    }
    return {0, 0};
}

std::uint64_t statsNumber(const std::string& json, const std::string& key) {
    const auto at = json.find("\"" + key + "\":");
    return at == std::string::npos ? 0 : std::stoull(json.substr(at + key.size() + 3));
}

void flipByteOf(const fs::path& file, const std::string& tag) {
    std::string bytes = vtex::test::readText(file);
    const auto [offset, size] = sectionSpan(bytes, tag);
    ASSERT_GT(size, 8u) << tag;
    bytes[offset + size / 2] = char(bytes[offset + size / 2] ^ 0x20);
    std::ofstream(file, std::ios::binary | std::ios::trunc) << bytes;
}

}  // namespace

// `vtex render` reads each level of a .vto when a ray first uses it (octree::openVto): a damaged
// level no ray uses does not stop it, a damaged level it uses fails cleanly mid-render (exit 3,
// naming the file and the section, no image), and stats.json says how much of the file it read.
// A texel of 128³ voxels: its coarse levels take their density profile from level 6
// (octree::DensityProfile), so a view that marches them reads levels 0 … 6, not level 7.
TEST(RenderCli, ReadsOnlyTheLevelsItUsesAndADamagedUsedLevelExitsThree) {
    const fs::path dir = makeSceneDir("lazy", "", 7);
    const std::string original = vtex::test::readText(dir / "t.vto");
    const auto render = [&](const std::string& name) {
        return runVtex({"render", (dir / "scene.toml").string(), "-o", (dir / (name + ".exr")).string(), "--stats",
                        (dir / (name + ".json")).string(), "--lod-bias", "2", "--threads", "2", "--quiet"});
    };
    const auto clean = render("clean");
    ASSERT_EQ(clean.exitStatus, 0) << clean.err;
    const std::string stats = vtex::test::readText(dir / "clean.json");
    const std::uint64_t read = statsNumber(stats, "vto_bytes_read");
    EXPECT_EQ(statsNumber(stats, "vto_file_bytes"), original.size());
    // The deepest level read: the one whose section ends where the bytes read do.
    int deepest = -1;
    for (int l = 0; l <= 7; ++l) {
        const auto [offset, size] = sectionSpan(original, "LV0" + std::to_string(l));
        if (offset + size == read) deepest = l;
    }
    ASSERT_GE(deepest, 1) << stats;  // some level is read during the render, not at load
    ASSERT_LT(deepest, 7) << stats;

    flipByteOf(dir / "t.vto", "LV07");  // unused
    const auto unused = render("unused");
    ASSERT_EQ(unused.exitStatus, 0) << unused.err;
    EXPECT_EQ(vtex::test::readText(dir / "unused.exr"), vtex::test::readText(dir / "clean.exr"));

    std::ofstream(dir / "t.vto", std::ios::binary | std::ios::trunc) << original;
    const std::string used = "LV0" + std::to_string(deepest);
    flipByteOf(dir / "t.vto", used);
    const auto damaged = render("damaged");
    EXPECT_EQ(damaged.exitStatus, 3) << damaged.err;
    EXPECT_NE(damaged.err.find("t.vto"), std::string::npos) << damaged.err;
    EXPECT_NE(damaged.err.find("section '" + used + "'"), std::string::npos) << damaged.err;
    EXPECT_EQ(vtex::test::lineCount(damaged.err), 1u) << damaged.err;
    EXPECT_FALSE(fs::exists(dir / "damaged.exr"));
    // vtex inspect still checks every section at once, the unused one too.
    std::ofstream(dir / "t.vto", std::ios::binary | std::ios::trunc) << original;
    flipByteOf(dir / "t.vto", "LV07");
    const auto inspect = runVtex({"inspect", (dir / "t.vto").string()});
    EXPECT_EQ(inspect.exitStatus, 3) << inspect.err;
    EXPECT_NE((inspect.out + inspect.err).find("LV07"), std::string::npos) << inspect.out << inspect.err;
}

// --rows A:B writes those rows of the image, exactly as the whole render has them, and says which
// in stats.json; a range that is malformed, empty or past the image's height is bad usage.
TEST(RenderCli, RowsRenderThoseRowsOfTheWholeImage) {
    const fs::path dir = makeSceneDir("rows");
    const std::string scene = (dir / "scene.toml").string();
    const auto whole = runVtex({"render", scene, "-o", (dir / "whole.exr").string(), "--quiet"});
    ASSERT_EQ(whole.exitStatus, 0) << whole.err;
    const auto part = runVtex({"render", scene, "-o", (dir / "part.exr").string(), "--rows", "7:19", "--stats",
                               (dir / "part.json").string(), "--quiet"});
    ASSERT_EQ(part.exitStatus, 0) << part.err;
    const Image all = readExr(dir / "whole.exr"), rows = readExr(dir / "part.exr");
    ASSERT_EQ(rows.width, 40);
    ASSERT_EQ(rows.height, 12);
    const std::vector<float> expected(all.rgba.begin() + 7 * 40 * 4, all.rgba.begin() + 19 * 40 * 4);
    EXPECT_EQ(rows.rgba, expected);
    const std::string stats = vtex::test::readText(dir / "part.json");
    EXPECT_NE(stats.find("\"row_begin\": 7"), std::string::npos) << stats;
    EXPECT_NE(stats.find("\"row_end\": 19"), std::string::npos) << stats;
    EXPECT_NE(stats.find("\"height\": 30"), std::string::npos) << stats;
    for (const char* command : {"render", "reference"})
        for (const char* bad : {"7", "7:", "a:9", "9:9", "9:3", "-1:4", "0:31"}) {
            const auto r = runVtex({command, scene, "-o", (dir / "bad.exr").string(), "--rows", bad});
            EXPECT_EQ(r.exitStatus, 2) << command << " --rows " << bad << ": " << r.err;
            EXPECT_NE(r.err.find("--rows"), std::string::npos) << r.err;
            EXPECT_FALSE(fs::exists(dir / "bad.exr"));
        }
    // The image's height is the one --height sets.
    const auto shorter = runVtex({"render", scene, "-o", (dir / "bad.exr").string(), "--height", "20", "--rows", "0:25"});
    EXPECT_EQ(shorter.exitStatus, 2) << shorter.err;
}
