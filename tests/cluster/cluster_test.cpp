// `vtex run --executor slurm` on a real Slurm: the one-node cluster scripts/slurm-cluster.sh
// starts on this machine (ctest's fixture `slurm`, tests/cluster/CMakeLists.txt). A submission's
// outputs are the bytes a local run makes; a cancelled tile is all a rerun submits again, with
// what depends on it; a folder whose jobs are queued refuses a second submission and a local run
// (issue 18).
#include "pipeline_project.h"
#include "run_vtex.h"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <thread>

namespace fs = std::filesystem;
using vtex::test::runVtex;
using Json = nlohmann::json;

namespace {

// The pipeline the tests submit: two texels, a texel render in four tiles, a plain texel
// render, a reference and a comparison of the tiled render against the reference.
fs::path makeClusterProject(const std::string& name) {
    const fs::path dir = vtex::test::makeProject(name);
    vtex::test::writeText(dir / "pipeline.toml", vtex::test::kGrassTexel + vtex::test::kCrossTexel + R"(
[[render]]
name = "grass-tiled"
scene = "hill.toml"
texels = { cover = "grass" }
tiles = 4

[[render]]
name = "cross-hill"
scene = "hill.toml"
texels = { cover = "cross" }

[[render]]
name = "grass-reference"
scene = "hill.toml"
texels = { cover = "grass" }
renderer = "reference"
spp = 4

[[compare]]
name = "tiled-vs-reference"
a = "grass-tiled"
b = "grass-reference"
)");
    return dir;
}

void useCluster() {
    // The fixture's cluster; vtex and the jobs it submits find it through SLURM_CONF.
    ::setenv("SLURM_CONF", VTEX_SLURM_CONF, 1);
}

struct StageLine {
    std::string state, job;
};

// `vtex run --status DIR`, parsed: stage → (state, job).
std::map<std::string, StageLine> stageStatus(const fs::path& out) {
    const auto r = runVtex({"run", "--status", out.string()});
    EXPECT_EQ(r.exitStatus, 0) << r.err;
    std::map<std::string, StageLine> stages;
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);) {
        std::istringstream words(line);
        std::string stage, state, job;
        words >> stage >> state >> job;
        if (stage.find('/') != std::string::npos) stages[stage] = {state, job};
    }
    return stages;
}

// Polls the status until no stage is queued or running (at most `seconds`).
std::map<std::string, StageLine> waitForJobs(const fs::path& out, int seconds = 600) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    for (;;) {
        auto stages = stageStatus(out);
        bool busy = false;
        for (const auto& [stage, s] : stages) busy = busy || s.state == "queued" || s.state == "running";
        if (!busy || std::chrono::steady_clock::now() > deadline) return stages;
        std::this_thread::sleep_for(std::chrono::milliseconds(500));
    }
}

Json jobsRecord(const fs::path& out) { return Json::parse(vtex::test::readText(out / "slurm/jobs.json")); }

std::set<std::string> submittedStages(const fs::path& out) {
    std::set<std::string> stages;
    const Json record = jobsRecord(out);  // (a temporary's ["jobs"] would not outlive the loop's start)
    for (const Json& j : record["jobs"]) stages.insert(j["stage"].get<std::string>());
    return stages;
}

// Every output of every stage the same bytes in both folders, the manifests the same keys and
// output hashes; a render's stats hold its timings, so they are not compared.
void expectSameOutputs(const fs::path& a, const fs::path& b) {
    std::size_t manifests = 0;
    for (const char* kind : {"sources", "samples", "builds", "tiles", "renders", "compares"}) {
        if (!fs::exists(a / kind)) continue;
        for (const auto& entry : fs::directory_iterator(a / kind)) {
            const std::string file = entry.path().filename().string();
            if (file.size() < 14 || file.substr(file.size() - 14) != ".manifest.json") continue;
            ++manifests;
            const Json ma = Json::parse(vtex::test::readText(entry.path()));
            const Json mb = Json::parse(vtex::test::readText(b / kind / file));
            // An assembled render's key holds its tiles' stats, and so their timings: only its
            // outputs can be compared.
            if (ma["details"].value("tiles", 1) == 1) {
                EXPECT_EQ(ma["key"], mb["key"]) << kind << "/" << file;
            }
            for (const auto& [role, output] : ma["outputs"].items()) {
                if (role == "stats") continue;
                EXPECT_EQ(output["hash"], mb["outputs"][role]["hash"]) << kind << "/" << file << " " << role;
                EXPECT_EQ(vtex::test::readText(a / kind / output["file"].get<std::string>()),
                          vtex::test::readText(b / kind / output["file"].get<std::string>()))
                    << kind << "/" << output["file"];
            }
        }
    }
    EXPECT_EQ(manifests, 14u) << "2 sources, 2 samples, 2 builds, 4 tiles, 3 renders, 1 compare";
}

TEST(Cluster, ASubmissionMakesTheBytesOfALocalRunAndIsNotRepeated) {
    useCluster();
    const fs::path dir = makeClusterProject("cluster_same");
    const fs::path pipeline = dir / "pipeline.toml", local = dir / "local", slurm = dir / "slurm-out";
    const auto l = runVtex({"run", pipeline.string(), "-o", local.string()});
    ASSERT_EQ(l.exitStatus, 0) << l.err;

    const auto submitted = runVtex({"run", pipeline.string(), "-o", slurm.string(), "--executor", "slurm"});
    ASSERT_EQ(submitted.exitStatus, 0) << submitted.err;
    EXPECT_NE(submitted.err.find("14 of 14 stages submitted"), std::string::npos) << submitted.err;
    const auto stages = waitForJobs(slurm);
    ASSERT_EQ(stages.size(), 14u);
    for (const auto& [stage, s] : stages) EXPECT_EQ(s.state, "done") << stage;
    // The tiles' jobs depend on the texels', the assemble's on the tiles'.
    const Json record = jobsRecord(slurm);
    for (const Json& j : record["jobs"])
        if (j["stage"] == "render/grass-tiled") {
            EXPECT_EQ(j["after"].size(), 4u) << j.dump();
        }
    expectSameOutputs(local, slurm);

    // Everything is cached now: nothing is submitted again, and the status says so. What a job
    // killed mid-write left (AtomicOutputFile's temporary) goes: no job lives, the submitter
    // holds the folder.
    const fs::path leftover = slurm / "renders" / ".cross-hill.exr.tmp.gone-host.999999.1.1";
    vtex::test::writeText(leftover, "half an image");
    const auto again = runVtex({"run", pipeline.string(), "-o", slurm.string(), "--executor", "slurm"});
    ASSERT_EQ(again.exitStatus, 0) << again.err;
    EXPECT_NE(again.err.find("0 of 14 stages submitted"), std::string::npos) << again.err;
    EXPECT_FALSE(fs::exists(leftover));
    for (const auto& [stage, s] : stageStatus(slurm)) EXPECT_EQ(s.state, "cached") << stage;
}

TEST(Cluster, ACancelledTileIsAllARerunSubmitsWithWhatDependsOnIt) {
    useCluster();
    const fs::path dir = makeClusterProject("cluster_cancel");
    const fs::path pipeline = dir / "pipeline.toml", local = dir / "local", out = dir / "slurm-out";
    ASSERT_EQ(runVtex({"run", pipeline.string(), "-o", local.string()}).exitStatus, 0);

    // Held, every job waits: deterministically pending when the tile is cancelled.
    const auto held = runVtex({"run", pipeline.string(), "-o", out.string(), "--executor", "slurm", "--sbatch-arg=--hold"});
    ASSERT_EQ(held.exitStatus, 0) << held.err;
    for (const auto& [stage, s] : stageStatus(out)) EXPECT_EQ(s.state, "queued") << stage;
    // While its jobs are queued, the folder refuses another submission and a local run.
    const auto second = runVtex({"run", pipeline.string(), "-o", out.string(), "--executor", "slurm"});
    EXPECT_NE(second.exitStatus, 0);
    EXPECT_NE(second.err.find("still queued or running"), std::string::npos) << second.err;
    const auto localRun = runVtex({"run", pipeline.string(), "-o", out.string()});
    EXPECT_NE(localRun.exitStatus, 0);
    EXPECT_NE(localRun.err.find("still queued or running"), std::string::npos) << localRun.err;

    std::string tile, others;
    const Json record = jobsRecord(out);
    for (const Json& j : record["jobs"]) {
        if (j["stage"] == "tile/grass-tiled.2") tile = j["job"];
        else (others += ' ') += j["job"].get<std::string>();
    }
    ASSERT_FALSE(tile.empty());
    // (appends: GCC 12 warns falsely, -Wrestrict, on "literal" + std::string)
    std::string cancel = "scancel ", release = "scontrol release";
    cancel += tile;
    (release += others) += " >/dev/null";
    ASSERT_EQ(std::system(cancel.c_str()), 0);
    ASSERT_EQ(std::system(release.c_str()), 0);
    auto stages = waitForJobs(out);
    // The tile and what depends on it failed (Slurm cancels a job whose dependency cannot be met),
    // the rest is done.
    const std::set<std::string> lost = {"tile/grass-tiled.2", "render/grass-tiled", "compare/tiled-vs-reference"};
    for (const auto& [stage, s] : stages) EXPECT_EQ(s.state, lost.count(stage) ? "failed" : "done") << stage;

    const auto rerun = runVtex({"run", pipeline.string(), "-o", out.string(), "--executor", "slurm"});
    ASSERT_EQ(rerun.exitStatus, 0) << rerun.err;
    EXPECT_EQ(submittedStages(out), lost) << rerun.err;
    stages = waitForJobs(out);
    for (const auto& [stage, s] : stages) EXPECT_EQ(s.state, lost.count(stage) ? "done" : "cached") << stage;
    expectSameOutputs(local, out);
}

TEST(Cluster, BadUsageIsRefused) {
    useCluster();
    const fs::path dir = makeClusterProject("cluster_usage");
    EXPECT_EQ(runVtex({"run", "--status", (dir / "nothing-here").string()}).exitStatus, 3);
    EXPECT_EQ(runVtex({"run", (dir / "pipeline.toml").string(), "--executor", "slurm", "--dry-run"}).exitStatus, 2);
    EXPECT_EQ(runVtex({"run", (dir / "pipeline.toml").string(), "--executor", "pbs"}).exitStatus, 2);
    EXPECT_EQ(runVtex({"run"}).exitStatus, 2);
    // sbatch refuses an unknown partition: the submission fails whole, naming the stage.
    const auto bad = runVtex({"run", (dir / "pipeline.toml").string(), "-o", (dir / "bad").string(), "--executor", "slurm",
                              "--partition", "no-such-partition"});
    EXPECT_EQ(bad.exitStatus, 1);
    EXPECT_NE(bad.err.find("sbatch refused stage source/grass"), std::string::npos) << bad.err;
}

}  // namespace
