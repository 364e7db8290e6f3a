// The parts of the Slurm executor that need no cluster: the pipeline file's [slurm] table and the
// program runner it talks to Slurm through (tests/cluster runs it against a real one).
#include "pipeline_project.h"
#include "run_vtex.h"

#include <vtex/core/error.h>
#include <vtex/pipelines/pipeline.h>

#include "subprocess.h"

#include <gtest/gtest.h>

#include <chrono>

namespace fs = std::filesystem;
using vtex::pipelines::detail::runProcess;

namespace {

fs::path withSlurm(const std::string& name, const std::string& table) {
    const fs::path dir = vtex::test::makeProject(name);
    vtex::test::writeText(dir / "pipeline.toml", vtex::test::readText(dir / "pipeline.toml") + "\n[slurm]\n" + table);
    return dir / "pipeline.toml";
}

TEST(SlurmSettings, ThePipelineFileSetsWhatSbatchIsAsked) {
    const auto p = vtex::pipelines::loadPipeline(withSlurm(
        "slurm_settings", "partition = \"gpu\"\ntime = \"2:00:00\"\nmem = \"8G\"\ncpus = 6\nsbatch_args = [\"--qos=long\", \"--account=vfx\"]\n"));
    EXPECT_EQ(p.slurm.partition, "gpu");
    EXPECT_EQ(p.slurm.time, "2:00:00");
    EXPECT_EQ(p.slurm.mem, "8G");
    EXPECT_EQ(p.slurm.cpus, 6);
    EXPECT_EQ(p.slurm.sbatchArguments, (std::vector<std::string>{"--qos=long", "--account=vfx"}));
    // Without the table: the cluster's defaults, two CPUs for samples and builds.
    const auto plain = vtex::pipelines::loadPipeline(vtex::test::makeProject("slurm_none") / "pipeline.toml");
    EXPECT_EQ(plain.slurm, vtex::pipelines::SlurmSettings{});
    EXPECT_EQ(plain.slurm.cpus, 2);
}

TEST(SlurmSettings, BadValuesAreTheFilesErrorNamingTheKey) {
    for (const auto& [table, key] : std::vector<std::pair<std::string, std::string>>{
             {"cpus = 0\n", "slurm.cpus"},
             {"sbatch_args = \"--hold\"\n", "slurm.sbatch_args"},
             {"sbatch_args = [1]\n", "slurm.sbatch_args"},
             {"sbatch_args = [\"a\\nb\"]\n", "slurm.sbatch_args"},
             {"partition = 3\n", "slurm.partition"}}) {
        try {
            vtex::pipelines::loadPipeline(withSlurm("slurm_bad", table));
            ADD_FAILURE() << "accepted " << table;
        } catch (const vtex::InputError& e) {
            EXPECT_NE(std::string(e.what()).find(key), std::string::npos) << table << ": " << e.what();
        }
    }
}

TEST(SlurmSettings, TheProgramRunnerCapturesBothStreamsAndNeverHangs) {
    const auto r = runProcess({"sh", "-c", "echo out; echo err >&2; exit 7"});
    EXPECT_EQ(r.exitStatus, 7);
    EXPECT_EQ(r.out, "out\n");
    EXPECT_EQ(r.err, "err\n");
    // More than a pipe holds on both streams at once: poll reads them as they come.
    const auto big = runProcess({"sh", "-c", "head -c 300000 /dev/zero; head -c 300000 /dev/zero >&2"});
    EXPECT_EQ(big.out.size(), 300000u);
    EXPECT_EQ(big.err.size(), 300000u);
    const auto start = std::chrono::steady_clock::now();
    const auto slow = runProcess({"sleep", "30"}, 0.5);
    EXPECT_TRUE(slow.timedOut);
    EXPECT_EQ(slow.exitStatus, -1);
    EXPECT_LT(std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count(), 5.0);
    try {
        runProcess({"vtex-no-such-program"});
        ADD_FAILURE() << "started a program that does not exist";
    } catch (const std::runtime_error& e) {
        EXPECT_NE(std::string(e.what()).find("vtex-no-such-program"), std::string::npos) << e.what();
    }
    EXPECT_EQ(vtex::pipelines::detail::commandLine({"vtex", "run", "a b.toml", "it's"}), "vtex run 'a b.toml' 'it'\\''s'");
}

}  // namespace
