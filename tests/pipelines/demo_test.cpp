// `vtex demo` end to end at a small size: every figure is rendered and measured against its
// reference, the Fig. 4 series is compared, the error-against-time study is tabled, the report
// lists it all, its scenes render on their own afterwards, and a second run (or `vtex run` on the
// demo's own inputs) is entirely cached.
#include "run_vtex.h"

#include <vtex/render/image.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cmath>
#include <filesystem>
#include <map>
#include <string>

namespace fs = std::filesystem;
using vtex::test::runVtex;

namespace {

TEST(Demo, RendersEveryFigureReportsThemAndIsCachedTheSecondTime) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "demo_small";
    fs::remove_all(dir);
    const auto r = runVtex({"demo", "-o", dir.string(), "--resolution", "16", "--scale", "0.1", "--quiet"});
    ASSERT_EQ(r.exitStatus, 0) << r.err << r.out;
    EXPECT_NE(r.out.find("report.html"), std::string::npos) << r.out;

    const auto report = nlohmann::json::parse(vtex::test::readText(dir / "report.json"));
    EXPECT_TRUE(report["succeeded"].get<bool>());
    int renders = 0, compares = 0;
    for (const auto& stage : report["stages"]) {
        EXPECT_EQ(stage["status"], "ran") << stage["kind"] << " " << stage["name"];
        if (stage["kind"] == "render") {
            ++renders;
            const auto image = vtex::render::readExr(dir / "renders" / (stage["name"].get<std::string>() + ".exr"));
            double sum = 0;
            for (float v : image.rgba) {
                ASSERT_TRUE(std::isfinite(v)) << stage["name"];
                sum += v;
            }
            EXPECT_GT(sum, 0) << stage["name"] << " is black";
            EXPECT_TRUE(fs::exists(dir / "renders" / (stage["name"].get<std::string>() + ".png")));
        }
        if (stage["kind"] == "compare") {
            ++compares;
            EXPECT_GT(stage["details"]["rmse"].get<double>(), 0) << "a coarser level is a different image";
            // A coarser level is set against the finest, never taken for the truth.
            if (stage["name"].get<std::string>().ends_with("-vs-finest")) {
                EXPECT_EQ(stage["details"]["b"], "fig4-level-minus-0") << stage["name"];
            }
        }
    }
    EXPECT_EQ(renders, 32) << "Figs. 7, 6, 10, 9, 11, 1, 8, 5 and four levels of Fig. 4 (12), their 9 references, "
                              "and the study's 6 texel renders, 4 references and its truth";
    EXPECT_EQ(compares, 25) << "12 texel renders against their references, 3 levels against the finest, 10 in the study";
    // Every figure's error against its reference, at this size (77×58, texels of at most 16³,
    // 16-spp references): measured 0.0376 (Fig. 1), 0.0263 (10), 0.0788 (11; blocks thinner than
    // a 16³ voxel turn transparent), 0.0318 / 0.0200 / 0.0325 / 0.0359 (Fig. 4's four levels),
    // 0.0209 (5), 0.1227 (6; the horizon, where the reference's 16 samples alias), 0.0175 (7),
    // 0.0153 (8), 0.0167 (9). The renders are deterministic; each bound is 1.25× its measurement.
    const std::map<std::string, double> bounds = {
        {"fig1-brushed-vs-reference", 0.047},       {"fig10-fur-torus-vs-reference", 0.033},
        {"fig11-blocks-vs-reference", 0.099},       {"fig4-level-minus-0-vs-reference", 0.040},
        {"fig4-level-minus-1-vs-reference", 0.025}, {"fig4-level-minus-2-vs-reference", 0.041},
        {"fig4-level-minus-3-vs-reference", 0.045}, {"fig6-bush-field-vs-reference", 0.154},
        {"fig7-grass-hill-vs-reference", 0.022},    {"fig8-velvet-vs-reference", 0.019},
        {"fig9-forest-hill-vs-reference", 0.021},   {"fig5-topiary-vs-reference", 0.026}};
    int bounded = 0;
    for (const auto& stage : report["stages"]) {
        const auto bound = bounds.find(stage["name"].get<std::string>());
        if (stage["kind"] != "compare" || bound == bounds.end()) continue;
        ++bounded;
        EXPECT_LE(stage["details"]["rmse"].get<double>(), bound->second) << bound->first;
    }
    EXPECT_EQ(bounded, int(bounds.size())) << "every figure against its reference has its bound";
    // The study's table: every texel render has a speed-up at equal error (or a bound).
    bool studyFound = false;
    for (const auto& group : report["error_against_time"]) {
        if (group["truth"] != "study-truth") continue;
        studyFound = true;
        EXPECT_EQ(group["rows"].size(), 10u);
        for (const auto& row : group["rows"]) {
            if (row["renderer"] == "texel") {
                EXPECT_TRUE(row.contains("speedup_at_equal_error")) << row.dump();
            }
        }
    }
    EXPECT_TRUE(studyFound);
    // The report: the finest level's table is one of differences, and no level is a truth.
    const std::string html = vtex::test::readText(dir / "report.html");
    EXPECT_NE(html.find("Difference from fig4-level-minus-0"), std::string::npos);
    for (const char* level : {"fig4-level-minus-1", "fig4-level-minus-2", "fig4-level-minus-3"})
        EXPECT_EQ(html.find("Against " + std::string(level)), std::string::npos) << level;
    EXPECT_NE(r.out.find("error against run time"), std::string::npos) << r.out;

    // The scenes the demo leaves in DIR/inputs name the texels it built: `vtex render` takes them
    // as they are and draws what the pipeline drew, to the bit.
    for (const std::string figure : {"fig7-grass-hill", "fig10-fur-torus"}) {
        const fs::path alone = dir / (figure + "-alone.exr");
        const auto direct = runVtex({"render", (dir / "inputs" / (figure + ".toml")).string(), "-o", alone.string(), "-q"});
        ASSERT_EQ(direct.exitStatus, 0) << direct.err;
        EXPECT_EQ(vtex::render::readExr(alone).rgba, vtex::render::readExr(dir / "renders" / (figure + ".exr")).rgba) << figure;
        fs::remove(alone);
    }

    const auto again = runVtex({"demo", "-o", dir.string(), "--resolution", "16", "--scale", "0.1"});
    ASSERT_EQ(again.exitStatus, 0) << again.err;
    EXPECT_EQ(again.err.find("run    "), std::string::npos) << "nothing may run again:\n" << again.err;
    const auto rerun = runVtex({"run", (dir / "inputs" / "pipeline.toml").string()});
    ASSERT_EQ(rerun.exitStatus, 0) << rerun.err;
    EXPECT_EQ(rerun.err.find("run    "), std::string::npos) << "the demo's inputs are a plain pipeline:\n" << rerun.err;
}

TEST(Demo, RefusesABadResolutionOrScaleAsBadUsage) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "demo_bad";
    EXPECT_EQ(runVtex({"demo", "-o", dir.string(), "--resolution", "48"}).exitStatus, 2);
    EXPECT_EQ(runVtex({"demo", "-o", dir.string(), "--scale", "0"}).exitStatus, 2);
    EXPECT_FALSE(fs::exists(dir));
}

// Found by fuzz_cli.py (third campaign, fuzz/corpus-cli/regression_14): `vtex demo -o DIR --seed
// -1` was taken for the seed 2⁶⁴ − 1, which the demo wrote into DIR/inputs/pipeline.toml and then
// could not read back (TOML integers are signed 64-bit): exit 3, "not representable in 64 bits",
// naming a file of its own, with DIR/inputs left behind. A seed outside [0, 2⁶³ − 1] is bad
// usage, for `vtex pattern` too (where -1 silently made the mesh of seed 2⁶⁴ − 1).
TEST(Demo, FuzzASeedAPipelineCannotHoldIsBadUsage) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "demo_seed";
    fs::remove_all(dir);
    const std::string glb = (fs::path(VTEX_TEST_TMP) / "demo_seed.glb").string();
    fs::remove(glb);  // made by the end of an earlier run
    for (const std::string seed : {"-1", "9223372036854775808", "18446744073709551616", "1.5", "x"}) {
        for (const std::vector<std::string>& args : {std::vector<std::string>{"demo", "-o", dir.string(), "--seed", seed},
                                                     {"pattern", "grass", "-o", glb, "--seed", seed}}) {
            const auto r = runVtex(args);
            EXPECT_EQ(r.exitStatus, 2) << args[0] << " --seed " << seed << ": " << r.err;
            EXPECT_NE(r.err.find("--seed: must be a whole number from 0 to 9223372036854775807"), std::string::npos) << r.err;
        }
        EXPECT_FALSE(fs::exists(dir)) << seed;
        EXPECT_FALSE(fs::exists(glb)) << seed;
    }
    EXPECT_EQ(runVtex({"pattern", "grass", "-o", glb, "--seed", "9223372036854775807"}).exitStatus, 0);
}

}  // namespace
