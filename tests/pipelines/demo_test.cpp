// `vtex demo` end to end, small: every artifact it claims is written, readable by the next
// stage, and the summary's figures agree with the artifacts themselves.
#include "run_vtex.h"

#include <vtex/octree/octree.h>
#include <vtex/octree/volume.h>
#include <vtex/render/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;
using vtex::test::runVtex;

namespace {

fs::path freshDirectory(const std::string& name) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / name;
    fs::remove_all(dir);
    return dir;
}

TEST(Demo, RunsEveryExistingStageAndItsSummaryMatchesTheArtifacts) {
    const fs::path dir = freshDirectory("demo_small");
    const auto r = runVtex({"demo", "-o", dir.string(), "--resolution", "16", "--pattern", "grass",
                            "--pattern", "blocks", "--quiet"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_NE(r.out.find("grass"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("blocks"), std::string::npos) << r.out;

    const auto summary = nlohmann::json::parse(vtex::test::readText(dir / "demo.json"));
    ASSERT_EQ(summary["patterns"].size(), 2u);
    for (const auto& pattern : summary["patterns"]) {
        const std::string name = pattern["name"];
        for (const auto& file : pattern["files"]) EXPECT_TRUE(fs::exists(dir / file.get<std::string>())) << file;
        EXPECT_GT(pattern["triangles"].get<double>(), 0) << name;

        // The finest level read back holds what the summary says, and the source area
        // (ρ = area / (2 · voxel volume), so Σ ρ·volume is half the area), solid interiors aside.
        const auto volume = vtex::octree::readVtl(dir / (name + ".vtl"));
        EXPECT_EQ(volume.blocks.size(), pattern["occupied_voxels"].get<std::size_t>()) << name;
        if (volume.info.solidDensity == 0) {
            EXPECT_NEAR(volume.totalMass() / (0.5 * volume.info.sourceArea), 1.0, 1e-4) << name;
        }

        // The hill render: finite, not black, and the texel covers part of it.
        const auto image = vtex::render::readExr(dir / (name + "-hill.exr"));
        double sum = 0;
        for (float v : image.rgba) {
            ASSERT_TRUE(std::isfinite(v)) << name;
            sum += v;
        }
        EXPECT_GT(sum, 0) << name;
        EXPECT_GT(pattern["render"]["rays"].get<double>(), double(image.width * image.height)) << "shadow rays too";

        for (const std::string rule : {"neyret", "sggx"}) {
            const auto octree = vtex::octree::readVto(dir / (name + "-" + rule + ".vto"));
            EXPECT_DOUBLE_EQ(octree.compression(), pattern["compression_" + rule].get<double>()) << name;
            EXPECT_EQ(octree.levelCount(), 5u) << "16³ has levels 0..4";
            EXPECT_GT(octree.compression(), 0.0);
            EXPECT_LT(octree.compression(), 1.0);
        }
    }
}

TEST(Demo, RefusesAnUnknownPatternAndABadResolutionAsBadUsage) {
    const fs::path dir = freshDirectory("demo_bad");
    EXPECT_EQ(runVtex({"demo", "-o", dir.string(), "--resolution", "48"}).exitStatus, 2);
    EXPECT_EQ(runVtex({"demo", "-o", dir.string(), "--resolution", "16", "--pattern", "moss"}).exitStatus, 2);
}

}  // namespace
