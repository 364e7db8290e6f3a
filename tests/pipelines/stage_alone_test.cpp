// `vtex run --stage KIND/NAME` (RunOptions::stage): one stage alone, its inputs from the cache,
// makes what it makes inside a whole run: the same output bytes and the same cache key, so that
// a whole run afterwards finds everything cached. What a cluster job runs (issue 18).
#include "pipeline_project.h"
#include "run_vtex.h"

#include <vtex/core/error.h>
#include <vtex/pipelines/pipeline.h>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <filesystem>

namespace fs = std::filesystem;
using vtex::pipelines::RunOptions;
using vtex::pipelines::RunReport;
using Status = vtex::pipelines::StageRecord::Status;

namespace {

RunReport run(const fs::path& dir, const std::string& stage = "") {
    RunOptions options;
    options.stage = stage;
    return vtex::pipelines::runPipeline(vtex::pipelines::loadPipeline(dir / "pipeline.toml"), options);
}

nlohmann::json manifest(const fs::path& dir, const std::string& kind, const std::string& name) {
    return nlohmann::json::parse(vtex::test::readText(dir / "out" / (kind + "s") / (name + ".manifest.json")));
}

TEST(StageAlone, EachStageAloneMakesWhatItMakesInAWholeRun) {
    const fs::path whole = vtex::test::makeProject("stage_whole"), alone = vtex::test::makeProject("stage_alone");
    const RunReport all = run(whole);
    ASSERT_TRUE(all.succeeded());
    ASSERT_EQ(all.stages.size(), 9u);
    // In the order of the graph, each stage in a run of its own.
    for (const auto& stage : all.stages) {
        const RunReport one = run(alone, vtex::pipelines::stageId(stage.kind, stage.name));
        ASSERT_EQ(one.stages.size(), 1u);
        EXPECT_EQ(one.stages[0].status, Status::Ran) << stage.name << ": " << one.stages[0].message;
        const auto a = manifest(whole, stage.kind, stage.name), b = manifest(alone, stage.kind, stage.name);
        EXPECT_EQ(a["key"], b["key"]) << stage.kind << " " << stage.name;
        for (const auto& [role, output] : a["outputs"].items()) {
            // A render's stats hold its timings; everything else is the same bytes.
            if (role == "stats") continue;
            EXPECT_EQ(output["hash"], b["outputs"][role]["hash"]) << stage.kind << " " << stage.name << " " << role;
        }
    }
    EXPECT_FALSE(fs::exists(alone / "out/report.json")) << "a stage alone writes no report";
    const RunReport after = run(alone);
    ASSERT_TRUE(after.succeeded());
    for (const auto& stage : after.stages) EXPECT_EQ(stage.status, Status::Cached) << stage.kind << " " << stage.name;
    // Run alone again, a stage that is up to date is cached too.
    EXPECT_EQ(run(alone, "render/grass-hill").stages.at(0).status, Status::Cached);
}

TEST(StageAlone, AnInputNotInTheCacheOrAnUnknownIdIsRefused) {
    const fs::path dir = vtex::test::makeProject("stage_refused");
    try {
        run(dir, "render/grass-hill");
        FAIL() << "ran without its inputs";
    } catch (const vtex::InputError& e) {
        EXPECT_NE(std::string(e.what()).find("stage 'source/grass', an input of 'render/grass-hill', is not in the cache"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(fs::exists(dir / "out/renders/grass-hill.exr"));
    EXPECT_THROW(run(dir, "render/nope"), vtex::pipelines::UnknownStage);
    // The command line: an unknown id is bad usage (2) naming the stages there are, a missing
    // input bad input (3).
    const auto unknown = vtex::test::runVtex({"run", (dir / "pipeline.toml").string(), "--stage", "render/nope"});
    EXPECT_EQ(unknown.exitStatus, 2);
    EXPECT_NE(unknown.err.find("render/grass-hill"), std::string::npos) << unknown.err;
    const auto missing = vtex::test::runVtex({"run", (dir / "pipeline.toml").string(), "--stage", "compare/grass-vs-cross"});
    EXPECT_EQ(missing.exitStatus, 3) << missing.err;
    EXPECT_NE(missing.err.find("is not in the cache"), std::string::npos) << missing.err;
    // Its one source, then the stage: it runs.
    ASSERT_EQ(vtex::test::runVtex({"run", (dir / "pipeline.toml").string(), "--stage", "source/cross"}).exitStatus, 0);
    EXPECT_EQ(run(dir, "source/cross").stages.at(0).status, Status::Cached);
}

}  // namespace
