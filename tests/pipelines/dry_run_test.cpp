// `vtex run --dry-run` (planPipeline): which stages would run and why — no earlier run, a changed
// parameter, a changed input, a missing or edited output, an input that runs first — and nothing
// written; `--strict` refuses an unknown key; the ETA's arithmetic (estimateRemainingSeconds).
#include "pipeline_project.h"
#include "run_vtex.h"

#include <vtex/pipelines/pipeline.h>
#include <vtex/pipelines/run_observer.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <map>

namespace fs = std::filesystem;
using vtex::pipelines::PlannedStage;
using vtex::pipelines::StageTiming;
using vtex::test::makeProject;
using vtex::test::readText;
using vtex::test::runVtex;
using vtex::test::writeText;

namespace {

std::map<std::string, PlannedStage> plan(const fs::path& dir) {
    std::map<std::string, PlannedStage> out;
    for (const PlannedStage& p : vtex::pipelines::planPipeline(vtex::pipelines::loadPipeline(dir / "pipeline.toml"), {}))
        out[p.kind + " " + p.name] = p;
    return out;
}

std::map<std::string, std::string> reasonsOfRunning(const std::map<std::string, PlannedStage>& plan) {
    std::map<std::string, std::string> out;
    for (const auto& [stage, p] : plan)
        if (p.runs) out[stage] = p.reason;
    return out;
}

// Every file under `dir` with its size and modification time: what "nothing written" compares
// (files only: putting the deleted PNG back touches its folder).
std::map<std::string, std::pair<std::uintmax_t, fs::file_time_type>> snapshot(const fs::path& dir) {
    std::map<std::string, std::pair<std::uintmax_t, fs::file_time_type>> out;
    if (!fs::exists(dir)) return out;
    for (const auto& entry : fs::recursive_directory_iterator(dir))
        if (entry.is_regular_file()) out[entry.path().string()] = {entry.file_size(), entry.last_write_time()};
    return out;
}

void replaceOnce(const fs::path& file, const std::string& from, const std::string& to) {
    std::string text = readText(file);
    const auto at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    writeText(file, text.replace(at, from.size(), to));
}

TEST(DryRun, AFreshProjectRunsEverythingAndWritesNothing) {
    const fs::path dir = makeProject("dry_fresh");
    const auto planned = plan(dir);
    ASSERT_EQ(planned.size(), 9u) << "2 sources, 2 samples, 2 builds, 2 renders, 1 compare";
    for (const auto& [stage, p] : planned) {
        EXPECT_TRUE(p.runs) << stage;
        // The sources have no earlier run; the rest wait for them.
        if (p.kind == "source")
            EXPECT_EQ(p.reason, "no earlier run") << stage;
        else
            EXPECT_NE(p.reason.find("runs first"), std::string::npos) << stage << ": " << p.reason;
        EXPECT_LT(p.earlierSeconds, 0) << stage;
    }
    EXPECT_FALSE(fs::exists(dir / "out")) << "a dry run creates no folder";

    const auto r = runVtex({"run", (dir / "pipeline.toml").string(), "--dry-run"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_NE(r.out.find("would run source grass: no earlier run"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("9 of 9 stages would run"), std::string::npos) << r.out;
    EXPECT_FALSE(fs::exists(dir / "out"));
}

TEST(DryRun, NamesTheChangedParameterTheMissingOutputAndTheChangedInput) {
    const fs::path dir = makeProject("dry_changes");
    const auto first = runVtex({"run", (dir / "pipeline.toml").string(), "--quiet"});
    ASSERT_EQ(first.exitStatus, 0) << first.err;
    const auto before = snapshot(dir / "out");
    {
        const auto planned = plan(dir);
        EXPECT_TRUE(reasonsOfRunning(planned).empty()) << "a run just made everything";
        for (const auto& [stage, p] : planned) EXPECT_GE(p.earlierSeconds, 0) << stage << ": the manifest's time";
    }

    // A render parameter: that render, and the comparison waiting for its image.
    replaceOnce(dir / "pipeline.toml", "hybrid = false", "hybrid = false\nspp = 4");
    EXPECT_EQ(reasonsOfRunning(plan(dir)),
              (std::map<std::string, std::string>{{"render cross-hill", "changed parameter: spp 1 → 4"},
                                                  {"compare grass-vs-cross", "input render 'cross-hill' runs first"}}));
    replaceOnce(dir / "pipeline.toml", "hybrid = false\nspp = 4", "hybrid = false");

    // A deleted output: its stage, named by the file.
    const fs::path png = dir / "out" / "renders" / "grass-hill.png";
    const std::string kept = readText(png);
    fs::remove(png);
    auto running = reasonsOfRunning(plan(dir));
    EXPECT_EQ(running["render grass-hill"], "missing output renders/grass-hill.png");
    writeText(png, kept);

    // An edited source file: its source stage names the input, what depends on it follows.
    writeText(dir / "cross.obj", readText(dir / "cross.obj") + "f 1 2 6\n");
    running = reasonsOfRunning(plan(dir));
    EXPECT_EQ(running["source cross"], "changed input: file");
    EXPECT_EQ(running["sample cross"], "input source 'cross' runs first");
    EXPECT_EQ(running.count("source grass"), 0u);
    EXPECT_EQ(running.count("render grass-hill"), 0u);

    // The CLI's answer; the output folder as the real run left it (but the PNG put back above).
    const auto r = runVtex({"run", (dir / "pipeline.toml").string(), "--dry-run"});
    ASSERT_EQ(r.exitStatus, 0) << r.err;
    EXPECT_NE(r.out.find("would run source cross: changed input: file"), std::string::npos) << r.out;
    EXPECT_NE(r.out.find("cached    source grass"), std::string::npos) << r.out;
    const auto after = snapshot(dir / "out");
    EXPECT_EQ(after.size(), before.size());
    for (const auto& [file, state] : before) {
        if (file == png.string()) continue;
        ASSERT_TRUE(after.count(file)) << file << " went away";
        EXPECT_EQ(after.at(file), state) << file << " was written by a dry run";
    }
}

TEST(Strict, AnUnknownKeyIsBadUsageNamingTheFileAndKey) {
    const fs::path dir = makeProject("strict");
    replaceOnce(dir / "pipeline.toml", "hybrid = false", "hybrid = false\nsamples_per_pixel = 4");
    const auto strict = runVtex({"run", (dir / "pipeline.toml").string(), "--strict"});
    EXPECT_EQ(strict.exitStatus, 2) << strict.err;
    EXPECT_NE(strict.err.find("pipeline.toml: unknown key 'render[1].samples_per_pixel'"), std::string::npos) << strict.err;
    EXPECT_EQ(vtex::test::lineCount(strict.err), 1u) << strict.err;
    EXPECT_FALSE(fs::exists(dir / "out")) << "refused before anything runs";

    // Without --strict: a warning, and the run goes on (here a dry one).
    const auto lenient = runVtex({"run", (dir / "pipeline.toml").string(), "--dry-run"});
    EXPECT_EQ(lenient.exitStatus, 0) << lenient.err;
    EXPECT_NE(lenient.err.find("warning: " + (dir / "pipeline.toml").string() + ": unknown key 'render[1].samples_per_pixel'"),
              std::string::npos) << lenient.err;
}

TEST(Eta, WavesAddUpAndTheStagesOfAWaveShareTheSlots) {
    using State = StageTiming::State;
    // Wave 0: 4 s and 2 s on 2 slots → 4 s (the longest); wave 1: three stages of 3 s on 2 slots →
    // 4.5 s (their total over the slots), since 4.5 > 3.
    std::vector<StageTiming> stages = {{State::Pending, 0, 4}, {State::Pending, 0, 2}, {State::Pending, 1, 3},
                                       {State::Pending, 1, 3}, {State::Pending, 1, 3}};
    EXPECT_DOUBLE_EQ(*vtex::pipelines::estimateRemainingSeconds(stages, 2), 4 + 4.5);
    EXPECT_DOUBLE_EQ(*vtex::pipelines::estimateRemainingSeconds(stages, 1), 6 + 9);

    // Done stages cost nothing; a running one with its own progress: 30 % in 3 s leaves 7 s.
    stages[0].state = State::Done;
    stages[1] = {State::Running, 0, 2, 3.0, 0.3};
    EXPECT_NEAR(*vtex::pipelines::estimateRemainingSeconds(stages, 2), 7 + 4.5, 1e-12);
    // Without progress, its expected time less the elapsed, at least 0.
    stages[1].fraction = -1;
    stages[1].elapsedSeconds = 0.5;
    EXPECT_DOUBLE_EQ(*vtex::pipelines::estimateRemainingSeconds(stages, 2), 1.5 + 4.5);
    stages[1].elapsedSeconds = 5;
    EXPECT_DOUBLE_EQ(*vtex::pipelines::estimateRemainingSeconds(stages, 2), 0 + 4.5);

    // A stage still to do with no earlier time: no estimate; once it is done, one again.
    stages[3].expectedSeconds = -1;
    EXPECT_FALSE(vtex::pipelines::estimateRemainingSeconds(stages, 2).has_value());
    stages[3].state = State::Done;
    EXPECT_DOUBLE_EQ(*vtex::pipelines::estimateRemainingSeconds(stages, 2), 3);
    for (auto& s : stages) s.state = State::Done;
    EXPECT_DOUBLE_EQ(*vtex::pipelines::estimateRemainingSeconds(stages, 2), 0);
}

TEST(Eta, APlannedRunExpectsEachStageToTakeWhatItTookBefore) {
    const fs::path dir = makeProject("eta_plan");
    vtex::pipelines::RunOptions options;
    const auto pipeline = vtex::pipelines::loadPipeline(dir / "pipeline.toml");
    const auto report = vtex::pipelines::runPipeline(pipeline, options);
    ASSERT_TRUE(report.succeeded());
    options.force = true;
    std::map<std::string, double> took;
    for (const auto& s : report.stages) took[s.kind + " " + s.name] = s.seconds;
    for (const PlannedStage& p : vtex::pipelines::planPipeline(pipeline, options)) {
        EXPECT_TRUE(p.runs);
        EXPECT_EQ(p.reason, "forced (--force)");
        EXPECT_DOUBLE_EQ(p.earlierSeconds, took.at(p.kind + " " + p.name)) << p.kind << " " << p.name;
    }
}

}  // namespace
