// submitPipeline: the stages a local run would run, each as one sbatch job chained to its
// inputs' jobs (slurm.h).
#include <vtex/pipelines/slurm.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/folder_lock.h>
#include <vtex/core/memory_budget.h>

#include "slurm_jobs.h"
#include "stage_graph.h"
#include "subprocess.h"

#include <chrono>
#include <ctime>
#include <map>

namespace vtex::pipelines {
namespace {

namespace fs = std::filesystem;
using detail::Stage;

std::string utcNow() {
    const std::time_t now = std::chrono::system_clock::to_time_t(std::chrono::system_clock::now());
    std::tm tm{};
    gmtime_r(&now, &tm);
    char text[32];
    std::strftime(text, sizeof text, "%Y-%m-%dT%H:%M:%SZ", &tm);
    return text;
}

// What a stage's kind asks of the cluster: renders and tiles a whole node, an assemble (a render
// made of tiles) stacks rows on one CPU, samples and builds run their parallel loops on `cpus`.
struct Resources {
    bool wholeNode = false;
    int cpus = 1;
};

Resources resourcesOf(const std::vector<Stage>& stages, const Stage& stage, const SlurmSettings& settings) {
    if (stage.kind == "tile") return {true, 0};
    if (stage.kind == "render") {
        bool assemble = !stage.inputs.empty();
        for (std::size_t input : stage.inputs) assemble = assemble && stages[input].kind == "tile";
        return assemble ? Resources{false, 1} : Resources{true, 0};
    }
    if (stage.kind == "sample" || stage.kind == "build") return {false, settings.cpus};
    return {false, 1};
}

// The job's script: the one command it runs, readable by whoever debugs the job.
std::string jobScript(const std::vector<std::string>& command, const std::string& id, const Pipeline& pipeline) {
    return "#!/bin/sh\n# vtex stage " + id + " of " + fs::absolute(pipeline.file).string() +
           ", submitted by `vtex run --executor slurm` at " + utcNow() + "\nexec " + detail::commandLine(command) + "\n";
}

std::vector<std::string> sbatchCommand(const Stage& stage, const Resources& resources, const SlurmSettings& s,
                                       const std::vector<std::string>& after, const fs::path& log, const fs::path& script) {
    std::vector<std::string> argv = {"sbatch", "--parsable", "--job-name=vtex:" + stageId(stage.kind, stage.name),
                                     "--output=" + log.string()};
    if (!s.partition.empty()) argv.push_back("--partition=" + s.partition);
    if (!s.time.empty()) argv.push_back("--time=" + s.time);
    if (!s.mem.empty()) argv.push_back("--mem=" + s.mem);
    if (resources.wholeNode) {
        argv.push_back("--exclusive");
        if (s.mem.empty()) argv.push_back("--mem=0");  // all of the node's memory
    } else {
        argv.push_back("--cpus-per-task=" + std::to_string(resources.cpus));
    }
    if (!after.empty()) {
        std::string dependency = "--dependency=afterok";
        for (const std::string& job : after) dependency += ":" + job;
        argv.push_back(dependency);
        argv.push_back("--kill-on-invalid-dep=yes");  // an input failed: cancel, do not pend forever
    }
    argv.insert(argv.end(), s.sbatchArguments.begin(), s.sbatchArguments.end());
    argv.push_back(script.string());
    return argv;
}

// sbatch --parsable prints "id" or "id;cluster".
std::string submit(const std::vector<std::string>& argv, const std::string& id) {
    const detail::ProcessResult r = detail::runProcess(argv, 120);
    std::string job = r.out.substr(0, r.out.find_first_of(";\n"));
    if (r.exitStatus != 0 || job.empty() || job.find_first_not_of("0123456789") != std::string::npos)
        throw std::runtime_error("sbatch refused stage " + id + (r.timedOut ? " (no answer in 120 s)" : "") + ": " +
                                 (r.err.empty() ? r.out : r.err.substr(0, r.err.find_last_not_of("\n") + 1)) +
                                 " [" + detail::commandLine(argv) + "]");
    return job;
}

// Best effort, on the way out of a failed submission: its own error is the one to report.
void cancel(const std::vector<SubmittedJob>& jobs) noexcept {
    std::vector<std::string> argv = {"scancel"};
    for (const SubmittedJob& j : jobs) argv.push_back(j.job);
    try {
        if (argv.size() > 1) detail::runProcess(argv, 60);
    } catch (...) {
    }
}

}  // namespace

Submission submitPipeline(const Pipeline& pipeline, const RunOptions& options, const SlurmOptions& slurm) {
    const fs::path root = fs::absolute(options.output.empty() ? pipeline.output : options.output).lexically_normal();
    checkOutputFolder(root, {pipeline.file});
    MemoryBudget budget(0);
    std::vector<Stage> stages;
    std::vector<Omission> leftOut;
    detail::buildStageGraph(pipeline, root, options.force, budget, stages, leftOut);
    detail::createFolder(detail::slurmFolder(root) / "logs");
    // Exclusive while submitting: no local run meanwhile, and a job that starts waits (--wait).
    const FolderLock lock(root, options.waitForLock ? FolderLock::Mode::Wait : FolderLock::Mode::Refuse);
    // The last submission's jobs may still write the folder (asked of Slurm, which must answer).
    if (const auto last = detail::readJobsRecord(root)) detail::refuseWhileJobsLive(root, detail::liveJobs(*last));
    // No job of the last submission lives and no run holds the folder: what a job killed
    // mid-write (scancel, a lost node) left half-written can go.
    detail::prepareFolders(root, true);

    Submission submission{root, detail::jobsFile(root), detail::planStages(stages, root, options.force), {}};
    detail::JobsRecord record{fs::absolute(pipeline.file), root, utcNow(), {}};
    std::map<std::size_t, std::string> jobOf;  // stage index → its job
    try {
        // Written first, then after every job: a submitter killed half-way leaves a record of
        // what it submitted, and a submission of nothing one that says so.
        detail::writeJobsRecord(record);
        for (std::size_t i = 0; i < stages.size(); ++i) {
            if (!submission.plan[i].runs) continue;
            const Stage& stage = stages[i];
            const std::string id = stageId(stage.kind, stage.name);
            SubmittedJob job{id, "", {}, detail::slurmFolder(root) / (stage.kind + "." + stage.name + ".sh"), {}};
            for (std::size_t input : stage.inputs)
                if (jobOf.count(input)) job.after.push_back(jobOf[input]);
            std::vector<std::string> command = {slurm.vtex.string(), "run", fs::absolute(pipeline.file).string(), "-o",
                                                root.string(), "--stage", id, "--wait"};
            const Resources resources = resourcesOf(stages, stage, slurm.settings);
            if (!resources.wholeNode) command.insert(command.end(), {"--threads", std::to_string(resources.cpus)});
            if (options.force) command.push_back("--force");
            writeFileAtomically(job.script, jobScript(command, id, pipeline));
            fs::permissions(job.script, fs::perms::owner_exec | fs::perms::group_exec, fs::perm_options::add);
            const fs::path logPattern = detail::slurmFolder(root) / "logs" / (stage.kind + "." + stage.name + ".%j.log");
            job.job = submit(sbatchCommand(stage, resources, slurm.settings, job.after, logPattern, job.script), id);
            job.log = detail::slurmFolder(root) / "logs" / (stage.kind + "." + stage.name + "." + job.job + ".log");
            jobOf[i] = job.job;
            record.jobs.push_back(job);
            detail::writeJobsRecord(record);
        }
    } catch (...) {
        cancel(record.jobs);  // whole or absent: the record then names cancelled jobs only
        throw;
    }
    submission.jobs = record.jobs;
    return submission;
}

}  // namespace vtex::pipelines
