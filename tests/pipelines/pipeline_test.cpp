// `vtex run`: a small pipeline end to end, then the cache's promises — a second run is all
// cached; touching an input re-runs exactly what depends on it; a corrupted artifact is
// rebuilt; a run killed at any moment completes later without redoing finished stages; a
// pipeline file with an error is refused before anything runs.
#include "pipeline_project.h"
#include "run_vtex.h"

#include <vtex/core/error.h>
#include <vtex/octree/volume.h>
#include <vtex/pipelines/pipeline.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <chrono>
#include <filesystem>
#include <fstream>
#include <map>
#include <thread>

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;
using vtex::pipelines::RunReport;
using vtex::pipelines::StageRecord;
using Status = StageRecord::Status;

namespace {

using vtex::test::makeProject;
using vtex::test::writeText;

RunReport run(const fs::path& dir, bool force = false) {
    vtex::pipelines::RunOptions options;
    options.force = force;
    return vtex::pipelines::runPipeline(vtex::pipelines::loadPipeline(dir / "pipeline.toml"), options);
}

// "kind name" → status.
std::map<std::string, Status> statuses(const RunReport& report) {
    std::map<std::string, Status> out;
    for (const auto& s : report.stages) out[s.kind + " " + s.name] = s.status;
    return out;
}

std::set<std::string> stagesWith(const RunReport& report, Status status) {
    std::set<std::string> out;
    for (const auto& s : report.stages)
        if (s.status == status) out.insert(s.kind + " " + s.name);
    return out;
}

TEST(Pipeline, RunsEndToEndThenEverythingIsCached) {
    const fs::path dir = makeProject("end_to_end");
    const RunReport first = run(dir);
    ASSERT_TRUE(first.succeeded());
    EXPECT_EQ(first.stages.size(), 9u);
    EXPECT_EQ(stagesWith(first, Status::Ran).size(), 9u);
    for (const char* file : {"out/report.json", "out/report.html", "out/builds/grass.vto", "out/renders/grass-hill.exr",
                             "out/renders/cross-hill.png", "out/compares/grass-vs-cross.json"})
        EXPECT_TRUE(fs::is_regular_file(dir / file)) << file;
    const auto report = nlohmann::json::parse(vtex::test::readText(dir / "out/report.json"));
    EXPECT_TRUE(report["succeeded"].get<bool>());
    for (const auto& stage : report["stages"]) {
        // Resident memory of the process while the stage ran: at least its code and heap.
        EXPECT_GT(stage["peak_memory_bytes"].get<std::uint64_t>(), 1u << 20) << stage["name"];
        EXPECT_LE(stage["peak_memory_bytes"].get<std::uint64_t>(), report["peak_memory_bytes"].get<std::uint64_t>());
    }
    const auto metrics = nlohmann::json::parse(vtex::test::readText(dir / "out/compares/grass-vs-cross.json"));
    EXPECT_GT(metrics["rmse"].get<double>(), 0) << "two different texels render differently";
    // Each build reports its levels' fidelity to the source (issue 13's measure): the figures
    // `vtex inspect --source` measures on the same octree and mesh (a deterministic measure).
    for (const std::string texel : {"grass", "cross"}) {
        const auto build = nlohmann::json::parse(vtex::test::readText(dir / "out/builds" / (texel + ".manifest.json")));
        const auto inspected = vtex::test::runVtex({"inspect", (dir / "out/builds" / (texel + ".vto")).string(), "--json",
                                                    "--source", (dir / "out/sources" / (texel + ".glb")).string()});
        ASSERT_EQ(inspected.exitStatus, 0) << inspected.err;
        const auto perLevel = nlohmann::json::parse(inspected.out)["per_level"];
        const auto& levels = build["details"]["levels"];
        ASSERT_EQ(levels.size(), perLevel.size()) << texel;
        ASSERT_GT(levels.size(), 1u) << texel;
        for (std::size_t l = 0; l < levels.size(); ++l) {
            const auto& chords = perLevel[l]["chords_against_source"];
            const std::array<std::pair<const char*, nlohmann::json>, 3> figures = {
                {{"chord_error", chords["error"]},
                 {"beam_error_mean_abs", chords["beams"]["mean_abs"]},
                 {"beam_error_p95_abs", chords["beams"]["p95_abs"]}}};
            for (const auto& [name, measured] : figures) {
                ASSERT_TRUE(measured.is_number()) << texel << " level " << l << " " << name << ": " << measured;
                EXPECT_NEAR(levels[l][name].get<double>(), measured.get<double>(), 1e-9)
                    << texel << " level " << l << " " << name;
            }
            // The fitted levels' error, where the build fitted the level, as inspect's.
            if (chords["fitted"].is_null()) {
                EXPECT_TRUE(levels[l]["chord_error_fitted"].is_null()) << texel << " level " << l;
            } else {
                EXPECT_NEAR(levels[l]["chord_error_fitted"].get<double>(), chords["fitted"]["error"].get<double>(), 1e-9)
                    << texel << " level " << l;
                EXPECT_NEAR(levels[l]["level_fit_scale"].get<double>(), chords["fitted"]["scale"].get<double>(), 1e-9)
                    << texel << " level " << l;
            }
        }
    }

    const RunReport second = run(dir);
    ASSERT_TRUE(second.succeeded());
    EXPECT_EQ(stagesWith(second, Status::Cached).size(), 9u);

    const RunReport forced = run(dir, true);
    EXPECT_EQ(stagesWith(forced, Status::Ran).size(), 9u);
}

TEST(Pipeline, TouchingAnInputRerunsExactlyWhatDependsOnIt) {
    const fs::path dir = makeProject("touch");
    ASSERT_TRUE(run(dir).succeeded());

    // A new source file: its chain and the comparison re-run; the grass chain stays cached.
    writeText(dir / "cross.obj", vtex::test::readText(dir / "cross.obj") + "f 1 2 6\n");
    RunReport report = run(dir);
    ASSERT_TRUE(report.succeeded());
    EXPECT_EQ(stagesWith(report, Status::Ran),
              (std::set<std::string>{"source cross", "sample cross", "build cross", "render cross-hill",
                                     "compare grass-vs-cross"}));

    // A build parameter: the sample stays cached, the build and what reads it re-run.
    std::string pipeline = vtex::test::readText(dir / "pipeline.toml");
    pipeline.replace(pipeline.find("filter = \"neyret\""), 17, "filter = \"sggx\"");
    writeText(dir / "pipeline.toml", pipeline);
    report = run(dir);
    EXPECT_EQ(stagesWith(report, Status::Ran),
              (std::set<std::string>{"build cross", "render cross-hill", "compare grass-vs-cross"}));

    // A comment in the scene: both renders re-run, but their images are the same bytes, so the
    // comparison (keyed by image content) stays cached.
    writeText(dir / "hill.toml", vtex::test::readText(dir / "hill.toml") + "\n# an edit\n");
    report = run(dir);
    EXPECT_EQ(stagesWith(report, Status::Ran), (std::set<std::string>{"render grass-hill", "render cross-hill"}));

    // A dimmer light changes the images: the comparison re-runs too.
    std::string scene = vtex::test::readText(dir / "hill.toml");
    scene.replace(scene.find("color = [3.0, 3.0, 3.0]"), 23, "color = [2.0, 2.0, 2.0]");
    writeText(dir / "hill.toml", scene);
    report = run(dir);
    EXPECT_EQ(stagesWith(report, Status::Ran),
              (std::set<std::string>{"render grass-hill", "render cross-hill", "compare grass-vs-cross"}));

    // A render parameter, the level fit: that render alone, and the comparison its image feeds.
    pipeline = vtex::test::readText(dir / "pipeline.toml");
    pipeline.replace(pipeline.find("hybrid = false"), 14, "hybrid = false\nlevel_fit = false");
    writeText(dir / "pipeline.toml", pipeline);
    report = run(dir);
    EXPECT_EQ(stagesWith(report, Status::Ran), (std::set<std::string>{"render cross-hill", "compare grass-vs-cross"}));
}

TEST(Pipeline, ACorruptedCachedArtifactIsRebuilt) {
    const fs::path dir = makeProject("corrupt");
    ASSERT_TRUE(run(dir).succeeded());
    {
        std::fstream file(dir / "out/builds/grass.vto", std::ios::in | std::ios::out | std::ios::binary);
        file.seekp(40);
        file.put('\x7f');
    }
    const RunReport report = run(dir);
    ASSERT_TRUE(report.succeeded());
    // The rebuilt octree is the same content as before, so nothing downstream re-runs.
    EXPECT_EQ(stagesWith(report, Status::Ran), (std::set<std::string>{"build grass"}));
    // And a deleted one too.
    fs::remove(dir / "out/renders/cross-hill.exr");
    EXPECT_EQ(stagesWith(run(dir), Status::Ran), (std::set<std::string>{"render cross-hill"}));
}

TEST(Pipeline, AFailedStageStopsWhatDependsOnItOnly) {
    const fs::path dir = makeProject("failure");
    // A source that ingest refuses: an OBJ face with an index out of range.
    writeText(dir / "cross.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n");
    const RunReport report = run(dir);
    EXPECT_FALSE(report.succeeded());
    const auto s = statuses(report);
    EXPECT_EQ(s.at("source cross"), Status::Failed);
    EXPECT_EQ(s.at("sample cross"), Status::Skipped);
    EXPECT_EQ(s.at("render cross-hill"), Status::Skipped);
    EXPECT_EQ(s.at("compare grass-vs-cross"), Status::Skipped);
    EXPECT_EQ(s.at("render grass-hill"), Status::Ran) << "independent stages finish";
    // The CLI says which stage failed and exits non-zero.
    const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string(), "--quiet"});
    EXPECT_NE(r.exitStatus, 0);
    EXPECT_NE(r.err.find("source 'cross' failed"), std::string::npos) << r.err;
}

TEST(Pipeline, AKilledRunCompletesLaterWithoutRedoingFinishedStages) {
    // Kill the CLI with SIGKILL at several moments; each time, the next run must succeed and
    // report as cached every stage whose manifest existed before it started.
    // Delays grow until a run finishes before its kill, so that kills land all along the run
    // however fast or loaded the machine is.
    int partialRuns = 0;
    bool ranToCompletion = false;
    for (int delayMs = 10; !ranToCompletion && delayMs < 60000; delayMs = delayMs * 3 / 2 + 10) {
        const fs::path dir = makeProject("killed_" + std::to_string(delayMs));
        const pid_t child = fork();
        ASSERT_GE(child, 0);
        if (child == 0) {
            const std::string pipeline = (dir / "pipeline.toml").string();
            execl(VTEX_BINARY, VTEX_BINARY, "run", pipeline.c_str(), "--quiet", static_cast<char*>(nullptr));
            _exit(127);
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(delayMs));
        int status = 0;
        ranToCompletion = waitpid(child, &status, WNOHANG) == child;
        if (!ranToCompletion) {
            kill(child, SIGKILL);
            waitpid(child, &status, 0);
        }

        std::set<std::string> finished;
        for (const char* folder : {"sources", "samples", "builds", "renders", "compares"}) {
            if (!fs::is_directory(dir / "out" / folder)) continue;
            for (const auto& entry : fs::directory_iterator(dir / "out" / folder)) {
                const std::string file = entry.path().filename().string();
                const auto suffix = file.find(".manifest.json");
                // Hidden files are the atomic writer's temporaries, left by the kill.
                if (suffix != std::string::npos && file.front() != '.')
                    finished.insert(std::string(folder).substr(0, std::string(folder).size() - 1) + " " +
                                    file.substr(0, suffix));
            }
        }
        partialRuns += !finished.empty() && finished.size() < 9;
        const RunReport report = run(dir);
        ASSERT_TRUE(report.succeeded()) << "after a kill at " << delayMs << " ms";
        // Nothing hidden is left but the folder's lock file, which stays by design (folder_lock.h).
        for (const auto& entry : fs::recursive_directory_iterator(dir / "out")) {
            if (entry.path().filename() == ".vtex.lock") continue;
            EXPECT_NE(entry.path().filename().string().front(), '.') << "stale temporary " << entry.path();
        }
        for (const auto& stage : finished)
            EXPECT_EQ(statuses(report).at(stage), Status::Cached) << stage << " after a kill at " << delayMs << " ms";
    }
    EXPECT_GE(partialRuns, 1) << "no kill landed between the first and the last stage: the test proved nothing";
}

TEST(Pipeline, TexelsAreSampledOnlyAsFinelyAsARenderCanUseAndUnusedOnesAreNotBuilt) {
    const fs::path dir = makeProject("leave_out");
    std::string pipeline = vtex::test::readText(dir / "pipeline.toml");
    pipeline.replace(pipeline.find("resolution = 16"), 15, "resolution = 512");
    pipeline += "\n[[texel]]\nname = \"spare\"\nsource = \"grass\"\nresolution = 32\n";
    writeText(dir / "pipeline.toml", pipeline);

    RunReport report = run(dir);
    ASSERT_TRUE(report.succeeded());
    // A 48×36 image of a 2-unit hill from 3.6 units cannot use 512³ voxels.
    const auto grass = vtex::octree::readVtl(dir / "out/samples/grass.vtl");
    EXPECT_LT(grass.info.resolution(), 512u);
    EXPECT_GE(grass.info.resolution(), 8u);
    EXPECT_FALSE(fs::exists(dir / "out/samples/spare.vtl"));
    EXPECT_FALSE(fs::exists(dir / "out/builds/spare.vto"));
    std::map<std::string, std::string> reasons;
    for (const auto& o : report.leftOut) reasons[o.texel] = o.reason;
    EXPECT_NE(reasons["grass"].find("instead of 512"), std::string::npos) << reasons["grass"];
    EXPECT_NE(reasons["spare"].find("not built"), std::string::npos) << reasons["spare"];
    const auto json = nlohmann::json::parse(vtex::test::readText(dir / "out/report.json"));
    EXPECT_EQ(json["left_out"].size(), 2u);

    // A render four times as large needs two more levels: the grass is sampled again, finer.
    std::string scene = vtex::test::readText(dir / "hill.toml");
    scene.replace(scene.find("width = 48"), 10, "width = 192");
    scene.replace(scene.find("height = 36"), 11, "height = 144");
    writeText(dir / "hill.toml", scene);
    report = run(dir);
    ASSERT_TRUE(report.succeeded());
    EXPECT_EQ(statuses(report).at("sample grass"), Status::Ran);
    EXPECT_EQ(vtex::octree::readVtl(dir / "out/samples/grass.vtl").info.resolution(),
              std::min(512u, 4 * grass.info.resolution()));

    // Asking for every texel at its resolution: nothing is left out.
    pipeline = vtex::test::readText(dir / "pipeline.toml");
    pipeline.replace(pipeline.find("output = \"out\""), 14, "output = \"out\"\nfit_resolution = false");
    pipeline.replace(pipeline.find("resolution = 512"), 16, "resolution = 16");
    writeText(dir / "pipeline.toml", pipeline);
    report = run(dir);
    ASSERT_TRUE(report.succeeded());
    EXPECT_TRUE(report.leftOut.empty());
    EXPECT_TRUE(fs::exists(dir / "out/builds/spare.vto"));
    EXPECT_EQ(vtex::octree::readVtl(dir / "out/samples/grass.vtl").info.resolution(), 16u);
}

TEST(Pipeline, ReferenceRendersPutTexelRendersOnAnErrorAgainstTimeTable) {
    const fs::path dir = makeProject("error_table");
    std::string pipeline = vtex::test::readText(dir / "pipeline.toml");
    for (const auto& [name, spp] : {std::pair{"truth", 64}, {"reference-1", 1}, {"reference-4", 4}})
        pipeline += std::string("\n[[render]]\nname = \"") + name + "\"\nscene = \"hill.toml\"\ntexels = { cover = "
                    "\"cross\" }\nrenderer = \"reference\"\nspp = " + std::to_string(spp) + "\n";
    for (const char* a : {"cross-hill", "reference-1", "reference-4"})
        pipeline += std::string("\n[[compare]]\nname = \"") + a + "-vs-truth\"\na = \"" + a + "\"\nb = \"truth\"\n";
    writeText(dir / "pipeline.toml", pipeline);
    const RunReport report = run(dir);
    ASSERT_TRUE(report.succeeded());

    const auto json = nlohmann::json::parse(vtex::test::readText(dir / "out/report.json"));
    const auto& groups = json["error_against_time"];
    ASSERT_EQ(groups.size(), 2u);  // against "truth", and the original grass-vs-cross
    const auto& group = groups[0]["truth"] == "truth" ? groups[0] : groups[1];
    std::map<std::string, nlohmann::json> rows;
    for (const auto& row : group["rows"]) rows[row["render"].get<std::string>()] = row;
    ASSERT_EQ(rows.size(), 3u);
    EXPECT_EQ(rows["reference-1"]["renderer"], "reference");
    EXPECT_EQ(rows["cross-hill"]["filter"], "neyret");
    // More samples, less error against the 64-sample truth; more time.
    EXPECT_LT(rows["reference-4"]["rmse"].get<double>(), rows["reference-1"]["rmse"].get<double>());
    EXPECT_GT(rows["reference-1"]["rmse"].get<double>(), 0);
    const auto& speedup = rows["cross-hill"]["speedup_at_equal_error"];
    ASSERT_TRUE(speedup.is_object()) << rows["cross-hill"].dump();
    EXPECT_GT(speedup["value"].get<double>(), 0);
    const double texelSeconds = rows["cross-hill"]["seconds"].get<double>();
    const double texelError = rows["cross-hill"]["rmse"].get<double>();
    // The bound follows from where the texel render's error falls among the references'.
    const double e1 = rows["reference-1"]["rmse"].get<double>(), e4 = rows["reference-4"]["rmse"].get<double>();
    const std::string expectedBound = texelError >= e1 ? "at most" : texelError <= e4 ? "at least" : "interpolated";
    EXPECT_EQ(speedup["bound"], expectedBound);
    if (expectedBound == "at most") {
        EXPECT_NEAR(speedup["value"].get<double>() * texelSeconds, rows["reference-1"]["seconds"].get<double>(), 1e-9);
    }
    const std::string html = vtex::test::readText(dir / "out/report.html");
    // One study (three renders against the truth) with its plot; the texel-against-texel
    // comparison is a difference, not a study or a figure.
    EXPECT_NE(html.find("Studies: error against run time"), std::string::npos);
    EXPECT_NE(html.find("<h3>Against truth</h3>"), std::string::npos);
    EXPECT_NE(html.find("<svg class=\"plot\""), std::string::npos);
    EXPECT_NE(html.find("Difference from cross-hill"), std::string::npos);
    EXPECT_EQ(html.find("Against cross-hill"), std::string::npos);
    const auto statsTruth = nlohmann::json::parse(vtex::test::readText(dir / "out/renders/truth.stats.json"));
    EXPECT_EQ(statsTruth["renderer"], "reference-embedded");
    EXPECT_EQ(statsTruth["spp"], 64);
    // The build stage stored what a texel render with the default options measures of its source
    // (docs/pipelines.md); cross-hill, without the hybrid, measures its own.
    const auto statsGrass = nlohmann::json::parse(vtex::test::readText(dir / "out/renders/grass-hill.stats.json"));
    EXPECT_EQ(statsGrass["source_measures"], nlohmann::json::array({"stored"})) << statsGrass.dump();
    const auto statsCross = nlohmann::json::parse(vtex::test::readText(dir / "out/renders/cross-hill.stats.json"));
    EXPECT_EQ(statsCross["source_measures"], nlohmann::json::array({"measured"}));
}

TEST(Pipeline, AFileWithAnErrorIsRefusedBeforeAnythingRuns) {
    const fs::path dir = makeProject("refused");
    const std::string good = vtex::test::readText(dir / "pipeline.toml");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"resolution = 16", "resolution = 12"},               // texel[0].resolution
        {"source = \"cross\"", "source = \"nowhere\""},       // texel[1].source
        {"file = \"cross.obj\"", "file = \"missing.obj\""},   // source[1].file
        {"b = \"cross-hill\"", "b = 7"},                      // compare[0].b
        {"texels = { cover = \"grass\" }", "texels = { cover = \"moss\" }"},
        {"pattern = \"grass\"", "pattern = \"grass\"\nfile = \"cross.obj\""},
        {"texels = { cover = \"grass\" }", "texels = { moss = \"grass\" }"},  // not in the scene
        {"[pipeline]", "[pipeline"},                          // TOML syntax
        {"texels = { cover = \"grass\" }", "renderer = \"reference\""},  // nothing to draw in the cells
        {"count = 8", "count = 8\nvariant = \"radial\""},  // grass does not use a variant
        {"file = \"cross.obj\"", "file = \"cross.obj\"\nlean = 10"},  // a file has no pattern options
        {"file = \"cross.obj\"", "file = \"cross.obj\"\nup = \"w\""},   // an up axis is x, y or z
        {"file = \"cross.obj\"", "file = \"cross.obj\"\nfit = \"box\""},  // fit is keep or cell
        {"pattern = \"grass\"", "pattern = \"grass\"\nfit = \"cell\""},  // a pattern is already in the cell
    };
    const std::vector<std::string> keys = {"texel[0].resolution", "texel[1].source", "source[1].file",
                                           "compare[0].b", "render[0].texels.cover", "source[0]",
                                           "render[0].texels.moss", "line 2", "render[0].renderer",
                                           "source[0].variant", "source[1].lean", "source[1].up",
                                           "source[1].fit", "source[0].fit"};
    for (std::size_t i = 0; i < cases.size(); ++i) {
        std::string bad = good;
        bad.replace(bad.find(cases[i].first), cases[i].first.size(), cases[i].second);
        writeText(dir / "pipeline.toml", bad);
        const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string()});
        EXPECT_EQ(r.exitStatus, 3) << cases[i].second << "\n" << r.err;
        EXPECT_NE(r.err.find(keys[i]), std::string::npos) << r.err;
        EXPECT_NE(r.err.find("pipeline.toml"), std::string::npos) << r.err;
        EXPECT_EQ(vtex::test::lineCount(r.err), 1u) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out")) << "nothing may run: " << cases[i].second;
    }
}

}  // namespace

// Two stages that would write one file are refused before anything runs (issue 14, item 5): a
// compare `c` writes its manifest compares/c.manifest.json, which is the metrics file of a
// compare named `c.manifest`.
TEST(Pipeline, StagesThatWouldWriteOneFileAreRefusedBeforeAnythingRuns) {
    const fs::path dir = makeProject("collide");
    std::string pipeline = vtex::test::readText(dir / "pipeline.toml");
    pipeline += "\n[[compare]]\nname = \"c\"\na = \"grass-hill\"\nb = \"cross-hill\"\n"
                "\n[[compare]]\nname = \"c.manifest\"\na = \"grass-hill\"\nb = \"cross-hill\"\n";
    writeText(dir / "pipeline.toml", pipeline);
    try {
        run(dir);
        FAIL() << "the pipeline ran";
    } catch (const vtex::InputError& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("compare 'c'"), std::string::npos) << message;
        EXPECT_NE(message.find("compare 'c.manifest'"), std::string::npos) << message;
        EXPECT_NE(message.find("c.manifest.json"), std::string::npos) << message;
    }
    // Nothing ran: no stage left a manifest.
    if (fs::exists(dir / "out")) {
        for (const auto& entry : fs::recursive_directory_iterator(dir / "out")) {
            EXPECT_EQ(entry.path().string().find(".manifest.json"), std::string::npos) << entry.path();
        }
    }
}

// Found by fuzz_cli.py (fuzz/corpus-cli/regression_1): `vtex run` of a pipeline refused for
// an output collision exited 3 but left the empty output tree (out/, out/sources, …) behind; a
// refused command leaves nothing.
TEST(Pipeline, FuzzARefusedPipelineLeavesNoOutputDirectory) {
    const fs::path dir = makeProject("collide_leaves_nothing");
    writeText(dir / "pipeline.toml", vtex::test::readText(dir / "pipeline.toml") +
                                         "\n[[compare]]\nname = \"c\"\na = \"grass-hill\"\nb = \"cross-hill\"\n"
                                         "\n[[compare]]\nname = \"c.manifest\"\na = \"grass-hill\"\nb = \"cross-hill\"\n");
    const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string()});
    EXPECT_EQ(r.exitStatus, 3) << r.err;
    EXPECT_FALSE(fs::exists(dir / "out"));
}

// Found by fuzz_pipeline (fuzz/corpus-pipeline/regression_1, regression_2): a file name too long
// for the system or a link loop made the file check throw std::filesystem's own error, which
// `vtex run` reported as a failure (exit 1, "filesystem error: status: …") instead of bad input.
TEST(Pipeline, FuzzANameTooLongOrALinkLoopIsBadInputNamingTheKey) {
    const fs::path dir = makeProject("long_names");
    const std::string good = vtex::test::readText(dir / "pipeline.toml");
    fs::create_symlink("loop-b", dir / "loop-a");
    fs::create_symlink("loop-a", dir / "loop-b");
    const std::vector<std::pair<std::string, std::string>> cases = {
        {"file = \"cross.obj\"", "file = \"" + std::string(300, 'a') + ".obj\""},  // source[1].file
        {"scene = \"hill.toml\"", "scene = \"loop-a\""},                            // render[0].scene
    };
    const std::vector<std::string> keys = {"source[1].file: no such file", "render[0].scene: no such file"};
    for (std::size_t i = 0; i < cases.size(); ++i) {
        std::string bad = good;
        bad.replace(bad.find(cases[i].first), cases[i].first.size(), cases[i].second);
        writeText(dir / "pipeline.toml", bad);
        const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string()});
        EXPECT_EQ(r.exitStatus, 3) << r.err;
        EXPECT_NE(r.err.find(keys[i]), std::string::npos) << r.err;
        EXPECT_EQ(vtex::test::lineCount(r.err), 1u) << r.err;
    }
}

// The pipeline reader shares the fix of fuzz_scene's NUL finding (TomlReader::resolve): a
// pipeline's paths may not hold a NUL either (`scene = "hill.toml\u0000x"` read hill.toml;
// fuzz/corpus-pipeline/regression_3).
TEST(Pipeline, FuzzAPathHoldingANulIsRefusedNamingTheKey) {
    const fs::path dir = makeProject("nul_paths");
    const std::string good = vtex::test::readText(dir / "pipeline.toml");
    for (const auto& [from, to, key] : std::vector<std::array<std::string, 3>>{
             {"scene = \"hill.toml\"", "scene = \"hill.toml\\u0000x\"", "render[0].scene"},
             {"file = \"cross.obj\"", "file = \"cross.obj\\u0000\"", "source[1].file"},
             {"output = \"out\"", "output = \"o\\u0000ut\"", "pipeline.output"}}) {
        std::string bad = good;
        bad.replace(bad.find(from), from.size(), to);
        writeText(dir / "pipeline.toml", bad);
        const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string()});
        EXPECT_EQ(r.exitStatus, 3) << r.err;
        EXPECT_NE(r.err.find(key + ": a path may not hold a NUL character"), std::string::npos) << r.err;
    }
}

// A pattern source is checked as `vtex pattern` checks it, when the file is read (found while
// triaging fuzz_cli.py's `pattern brushed --count 2097152`, which grew past 6 GB): a count whose
// mesh would exceed what ingest reads (brushed, 10⁶ rings: about 4·10⁹ triangles) was accepted
// and the run ran out of memory; a lean the reader allows (±89°) but the pattern refuses (±80°)
// failed the source stage half-way through the run. Both are the file's error, exit 3, before
// anything runs.
TEST(Pipeline, FuzzAPatternSourceIsCheckedWhenTheFileIsRead) {
    const fs::path dir = makeProject("pattern_checked");
    const std::string good = vtex::test::readText(dir / "pipeline.toml");
    for (const auto& [from, to, message] : std::vector<std::array<std::string, 3>>{
             {"pattern = \"grass\"\ncount = 8", "pattern = \"brushed\"\ncount = 1000000",
              "source[0].count: 1000000 makes about"},
             {"count = 8", "count = 8\nlean = 85", "source[0]: lean must be within ±80 degrees"}}) {
        std::string bad = good;
        bad.replace(bad.find(from), from.size(), to);
        writeText(dir / "pipeline.toml", bad);
        const auto r = vtex::test::runVtex({"run", (dir / "pipeline.toml").string()});
        EXPECT_EQ(r.exitStatus, 3) << to << "\n" << r.err;
        EXPECT_NE(r.err.find(message), std::string::npos) << r.err;
        EXPECT_EQ(vtex::test::lineCount(r.err), 1u) << r.err;
        EXPECT_FALSE(fs::exists(dir / "out")) << "nothing may run: " << to;
    }
}
