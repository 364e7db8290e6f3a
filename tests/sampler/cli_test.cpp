// `vtex pattern | sample | build | inspect` end to end, and the refusals' exit statuses.
#include "run_vtex.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>

namespace vtex::test {
namespace {

namespace fs = std::filesystem;

fs::path tmp(const std::string& name) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "cli";
    fs::create_directories(dir);
    return dir / name;
}

// An option the pattern does not read is bad usage (issue 16): `--lean 1 --fluctuation 2
// --variant x` on the bush used to be ignored silently.
TEST(SamplerCli, APatternOptionThePatternDoesNotUseIsBadUsage) {
    const auto glb = tmp("unused.glb");
    std::filesystem::remove(glb);  // written by the end of an earlier run of this test
    for (const std::vector<std::string>& extra : {std::vector<std::string>{"--lean", "1"},
                                                  {"--fluctuation", "0.5"},
                                                  {"--variant", "radial"}}) {
        std::vector<std::string> args = {"pattern", "bush", "-o", glb.string()};
        args.insert(args.end(), extra.begin(), extra.end());
        const auto r = runVtex(args);
        EXPECT_EQ(r.exitStatus, 2) << extra[0] << ": " << r.err;
        EXPECT_NE(r.err.find(extra[0]), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("bush pattern does not use it"), std::string::npos) << r.err;
        EXPECT_FALSE(std::filesystem::exists(glb));
    }
    EXPECT_EQ(runVtex({"pattern", "grass", "-o", glb.string(), "--lean", "10", "--fluctuation", "0.1"}).exitStatus, 0);
    EXPECT_EQ(runVtex({"pattern", "brushed", "-o", glb.string(), "--variant", "radial"}).exitStatus, 0);
}

TEST(SamplerCli, PatternSampleBuildInspect) {
    const auto glb = tmp("grass.glb"), vtl = tmp("grass.vtl"), vto = tmp("grass.vto");
    auto r = runVtex({"pattern", "grass", "-o", glb.string(), "--seed", "4"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    r = runVtex({"sample", glb.string(), "-o", vtl.string(), "--resolution", "32", "--cyclic"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    r = runVtex({"build", vtl.string(), "-o", vto.string(), "--filter", "neyret", "--tolerance", "0.01"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    r = runVtex({"inspect", vto.string(), "--json"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_EQ(lineCount(r.out), 1u);
    const auto j = nlohmann::json::parse(r.out);
    EXPECT_EQ(j["filter"], "neyret") << r.out;
    EXPECT_EQ(j["per_level"].size(), 6u) << "32³ has levels 0..5";
    EXPECT_EQ(j["checksums"]["valid"], true);
    EXPECT_EQ(j["cyclic"], true);
    // The density profile's layer means (the PROF section): level 5's, 32 a side, and over every
    // axis their mean is the level's mean density of the statistics (each axis shares the level's
    // mass among its layers; two sums of the same densities in another order).
    ASSERT_TRUE(j.contains("density_profile")) << r.out;
    EXPECT_EQ(j["density_profile"]["level"], 5);
    for (const char* axis : {"x", "y", "z"}) {
        ASSERT_EQ(j["density_profile"][axis].size(), 32u) << axis;
        double mean = 0;
        for (const auto& v : j["density_profile"][axis]) mean += v.get<double>() / 32;
        EXPECT_NEAR(mean, j["per_level"][5]["mean_density"].get<double>(),
                    1e-9 * j["per_level"][5]["mean_density"].get<double>()) << axis;
    }
    r = runVtex({"inspect", vto.string()});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_NE(r.out.find("density profile (level 5 layer means"), std::string::npos) << r.out;
    r = runVtex({"inspect", vtl.string()});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_NE(r.out.find("fit error"), std::string::npos);
    EXPECT_NE(r.out.find("VOXL"), std::string::npos);
}

// `vtex inspect texel.vto --source mesh.glb`: each level's chord transmittance against the mesh
// (octree::measureChordTransmittance). The same chords at every level, so the same visibility;
// the error is transmittance − visibility; the 2000-leaf bush's coarse levels are too opaque
// (its leaves clustered in a shell, their mean density spread over whole voxels: measured −0.19
// at level 0, −0.04 at 3) and its finest level lets more through than level 0.
TEST(SamplerCli, InspectMeasuresEachLevelAgainstTheSource) {
    const auto glb = tmp("chords.glb"), vtl = tmp("chords.vtl"), vto = tmp("chords.vto");
    ASSERT_EQ(runVtex({"pattern", "bush", "-o", glb.string()}).exitStatus, 0);
    ASSERT_EQ(runVtex({"sample", glb.string(), "-o", vtl.string(), "-r", "32"}).exitStatus, 0);
    ASSERT_EQ(runVtex({"build", vtl.string(), "-o", vto.string()}).exitStatus, 0);
    auto r = runVtex({"inspect", vto.string(), "--json", "--source", glb.string()});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    const auto levels = nlohmann::json::parse(r.out)["per_level"];
    ASSERT_EQ(levels.size(), 6u);
    const double visibility = levels[0]["chords_against_source"]["visibility"].get<double>();
    EXPECT_GT(visibility, 0.3);
    EXPECT_LT(visibility, 1.0);
    for (const auto& level : levels) {
        const auto& c = level["chords_against_source"];
        EXPECT_EQ(c["visibility"].get<double>(), visibility);
        EXPECT_GT(c["transmittance"].get<double>(), 0.0);
        EXPECT_LE(c["transmittance"].get<double>(), 1.0);
        EXPECT_NEAR(c["error"].get<double>(), c["transmittance"].get<double>() - visibility, 1e-12);
        // Over beams of the level: |mean| ≤ mean |error| ≤ p95-ish bounds, noise a valid SE.
        const auto& b = c["beams"];
        EXPECT_LE(std::abs(b["mean"].get<double>()), b["mean_abs"].get<double>() + 1e-12);
        EXPECT_GE(b["p95_abs"].get<double>(), 0.0);
        EXPECT_LE(b["p95_abs"].get<double>(), 1.0);
        EXPECT_GE(b["noise"].get<double>(), 0.0);
        EXPECT_LE(b["noise"].get<double>(), 0.5 / 16 + 1e-12);  // 0.5/√256
    }
    // The coarse levels' densities, as stored, are too opaque along the chords (level 0 at 32³:
    // −0.19 with uniform voxels, −0.06 with its profiles in height and across).
    EXPECT_LT(levels[0]["chords_against_source"]["error"].get<double>(), -0.03);
    EXPECT_LT(levels[3]["chords_against_source"]["error"].get<double>(), -0.02);
    // The levels as the renderer fits them (issue 13's fix), on the same chords: at least the
    // coarse levels are fitted (up to the faithful levels' finest + 1), each with a positive
    // factor, and where the mean-density level is far off (|error| > 0.05) the fitted one's error
    // is at most half of it (measured at 32³: level 0 −0.19 → −0.04).
    ASSERT_TRUE(levels[0]["chords_against_source"]["fitted"].is_object());
    for (const auto& level : levels) {
        const auto& c = level["chords_against_source"];
        if (c["fitted"].is_null()) continue;
        const auto& f = c["fitted"];
        EXPECT_GT(f["scale"].get<double>(), 0.0);
        EXPECT_NEAR(f["error"].get<double>(), f["transmittance"].get<double>() - visibility, 1e-12);
        if (std::abs(c["error"].get<double>()) > 0.05) {
            EXPECT_LE(std::abs(f["error"].get<double>()), 0.5 * std::abs(c["error"].get<double>())) << level;
        }
    }
    EXPECT_LT(levels[0]["chords_against_source"]["fitted"]["scale"].get<double>(), 1.0);
    // At 32³ the density profile comes from level 5 and levels 0–2 carry it (≥ 8 layers a voxel).
    for (std::size_t l = 0; l < levels.size(); ++l) {
        EXPECT_EQ(levels[l]["chords_against_source"]["density_profile"].get<bool>(), l < 3) << l;
    }
    EXPECT_GT(levels[5]["chords_against_source"]["transmittance"].get<double>(),
              levels[0]["chords_against_source"]["transmittance"].get<double>());
    r = runVtex({"inspect", vto.string(), "--source", glb.string()});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_NE(r.out.find("against the source"), std::string::npos);
    EXPECT_NE(r.out.find("levels 0-2: each voxel's density varies with height, in x and in y as level 5's layer and column means"),
              std::string::npos)
        << r.out;
    // The build reports the same table when given the source.
    const auto built = runVtex({"build", vtl.string(), "-o", tmp("chords2.vto").string(), "--source", glb.string()});
    ASSERT_EQ(built.exitStatus, 0) << built.err;
    EXPECT_NE(built.err.find("against the source"), std::string::npos) << built.err;
    EXPECT_EQ(runVtex({"inspect", vtl.string(), "--source", glb.string()}).exitStatus, 2);
    EXPECT_EQ(runVtex({"inspect", vto.string(), "--source", tmp("missing.glb").string()}).exitStatus, 3);
}

TEST(SamplerCli, CorruptedFilesAreRefusedWithTheirSection) {
    const auto glb = tmp("bush.glb"), vtl = tmp("bush.vtl"), vto = tmp("bush.vto");
    ASSERT_EQ(runVtex({"pattern", "bush", "--leaves", "50", "-o", glb.string()}).exitStatus, 0);
    ASSERT_EQ(runVtex({"sample", glb.string(), "-o", vtl.string(), "-r", "16"}).exitStatus, 0);
    ASSERT_EQ(runVtex({"build", vtl.string(), "-o", vto.string()}).exitStatus, 0);
    std::string bytes = readText(vto);
    bytes[bytes.size() - 5] ^= 1;
    const auto bad = tmp("bad.vto");
    std::ofstream(bad, std::ios::binary) << bytes;
    auto r = runVtex({"inspect", bad.string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("section 'LV04'"), std::string::npos) << r.err;
    EXPECT_EQ(lineCount(r.err), 1u) << r.err;
    // A truncated .vtl given to build: exit 3, nothing written.
    const std::string vtlBytes = readText(vtl);
    const auto cut = tmp("cut.vtl");
    std::ofstream(cut, std::ios::binary) << vtlBytes.substr(0, vtlBytes.size() / 2);
    const auto out = tmp("never.vto");
    r = runVtex({"build", cut.string(), "-o", out.string()});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_NE(r.err.find("VOXL"), std::string::npos) << r.err;
    EXPECT_FALSE(fs::exists(out));
}

TEST(SamplerCli, UsageErrorsAndMemoryLimit) {
    const auto glb = tmp("fur.glb");
    ASSERT_EQ(runVtex({"pattern", "fur", "--count", "20", "-o", glb.string()}).exitStatus, 0);
    EXPECT_EQ(runVtex({"sample", glb.string(), "-o", tmp("x.vtl").string(), "-r", "100"}).exitStatus, 2);
    EXPECT_EQ(runVtex({"build", "in.vtl", "-o", "x.vto", "--filter", "median"}).exitStatus, 2);
    EXPECT_EQ(runVtex({"pattern", "lawn", "-o", "x.glb"}).exitStatus, 2);
    const auto never = tmp("huge.vtl");
    const auto r = runVtex({"sample", glb.string(), "-o", never.string(), "-r", "4096", "--max-memory", "64MiB"});
    EXPECT_EQ(r.exitStatus, 3);
    EXPECT_EQ(r.signal, 0);
    EXPECT_NE(r.err.find("max-memory"), std::string::npos) << r.err;
    // With no --max-memory the limit is half of this machine's memory (issue 14, item 4): the
    // largest resolution the format names is refused at once, with its estimate.
    const auto huge = runVtex({"sample", glb.string(), "-o", never.string(), "-r", "1048576"});
    EXPECT_EQ(huge.exitStatus, 3) << huge.err;
    EXPECT_NE(huge.err.find("needs about"), std::string::npos) << huge.err;
    EXPECT_FALSE(std::filesystem::exists(never));
    EXPECT_FALSE(fs::exists(never));
}

// Found by fuzz_cli.py (second campaign, fuzz/corpus-cli/regression_11): `vtex pattern
// brushed --variant radial --count 2097152` was accepted (the count is checked against 10⁷ only)
// and grew past 6 GB building about 10⁹ triangles, a mesh no other command would read. A count
// whose mesh exceeds what ingest accepts (sampler::kMaxPatternTriangles) is bad usage naming
// the option, refused before the work; one just inside is made.
TEST(SamplerCli, FuzzAPatternCountTooLargeToIngestIsBadUsage) {
    const auto glb = tmp("too_many.glb");
    std::filesystem::remove(glb);
    for (const std::vector<std::string>& args :
         {std::vector<std::string>{"pattern", "brushed", "--variant", "radial", "--count", "2097152"},
          {"pattern", "bush", "--leaves", "10000000"}}) {
        std::vector<std::string> command = args;
        command.insert(command.end(), {"-o", glb.string()});
        const auto r = runVtex(command);
        EXPECT_EQ(r.exitStatus, 2) << args[1] << ": " << r.err;
        EXPECT_NE(r.err.find(args[args.size() - 2] + ": " + args.back() + " makes about"), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("triangles, more than the 50000000 vtex ingests"), std::string::npos) << r.err;
        EXPECT_EQ(lineCount(r.err), 1u) << r.err;
        EXPECT_FALSE(fs::exists(glb));
    }
    EXPECT_EQ(runVtex({"pattern", "brushed", "--variant", "radial", "--count", "200", "-o", glb.string()}).exitStatus, 0);
    EXPECT_TRUE(fs::exists(glb));
}

// Found by fuzz_cli.py (third campaign; fuzz/corpus-cli/regression_12): `vtex build IN -o
// out.vto --source small.exr` wrote the octree, then read the source and exited 3, leaving
// out.vto behind; a missing source did the same, and with -q the source was not read at all.
// The source is read before any output is written.
TEST(SamplerCli, FuzzABadBuildSourceLeavesNoOctree) {
    const auto glb = tmp("build_source.glb"), vtl = tmp("build_source.vtl"), vto = tmp("build_source.vto");
    ASSERT_EQ(runVtex({"pattern", "bush", "--count", "40", "-o", glb.string()}).exitStatus, 0);
    ASSERT_EQ(runVtex({"sample", glb.string(), "-o", vtl.string(), "-r", "8"}).exitStatus, 0);
    std::ofstream(tmp("not_a_mesh.exr")) << "x";
    for (const std::vector<std::string>& extra :
         {std::vector<std::string>{"--source", tmp("not_a_mesh.exr").string()},
          {"--source", tmp("missing.glb").string()},
          {"-q", "--source", tmp("missing.glb").string()}}) {
        fs::remove(vto);
        std::vector<std::string> args = {"build", vtl.string(), "-o", vto.string()};
        args.insert(args.end(), extra.begin(), extra.end());
        const auto r = runVtex(args);
        EXPECT_EQ(r.exitStatus, 3) << extra.back() << ": " << r.err;
        EXPECT_NE(r.err.find("vtex: error: " + extra.back() + ": "), std::string::npos) << r.err;
        EXPECT_EQ(lineCount(r.err), 1u) << r.err;  // no status line: nothing was built
        EXPECT_FALSE(fs::exists(vto)) << "the octree was left behind: " << extra.back();
    }
    EXPECT_EQ(runVtex({"build", vtl.string(), "-o", vto.string(), "--source", glb.string()}).exitStatus, 0);
    EXPECT_TRUE(fs::exists(vto));
}

}  // namespace
}  // namespace vtex::test
