#include "run_slurm.h"

#include <vtex/core/error.h>

#include <algorithm>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <map>

namespace vtex::cli {

namespace fs = std::filesystem;

void addSlurmOptions(CLI::App& app, SlurmFlags& flags) {
    app.add_option("--executor", flags.executor,
                   "Where the stages run: local (this process, the default) or slurm (one sbatch job per stage that is "
                   "not cached, chained by dependencies; returns once they are submitted)")
        ->check(CLI::IsMember({"local", "slurm"}));
    app.add_option("--partition", flags.partition, "Slurm: the partition of every job (default: [slurm] partition)");
    app.add_option("--time", flags.time, "Slurm: each job's time limit, as sbatch --time takes it (default: [slurm] time)");
    app.add_option("--mem", flags.mem,
                   "Slurm: each job's memory, as sbatch --mem takes it (default: [slurm] mem; renders then take the "
                   "node's whole memory, other stages the cluster's default)");
    app.add_option("--cpus", flags.cpus, "Slurm: CPUs of a sample or build job (default: [slurm] cpus, 2)")
        ->check(CLI::Range(1, 4096));
    app.add_option("--sbatch-arg", flags.sbatchArguments,
                   "Slurm: one more sbatch argument for every job, after vtex's own (repeatable; a value that "
                   "starts with a dash goes after an equals sign, as in --sbatch-arg=-qlong)")
        ->allow_extra_args(false);
    app.add_option("--status", flags.status,
                   "Show each stage of the last Slurm submission to this output folder: cached, queued, running, "
                   "done, failed or stale, with its job and a failed job's log; PIPELINE is not needed");
}

void submitToSlurm(const pipelines::Pipeline& pipeline, const pipelines::RunOptions& options, const SlurmFlags& flags,
                   const GlobalOptions& global) {
    pipelines::SlurmOptions slurm;
    slurm.settings = pipeline.slurm;
    if (!flags.partition.empty()) slurm.settings.partition = flags.partition;
    if (!flags.time.empty()) slurm.settings.time = flags.time;
    if (!flags.mem.empty()) slurm.settings.mem = flags.mem;
    if (flags.cpus > 0) slurm.settings.cpus = flags.cpus;
    slurm.settings.sbatchArguments.insert(slurm.settings.sbatchArguments.end(), flags.sbatchArguments.begin(),
                                          flags.sbatchArguments.end());
    // The jobs run this very program: on a cluster it must sit on the shared filesystem.
    std::error_code error;
    slurm.vtex = fs::read_symlink("/proc/self/exe", error);
    if (error) throw std::runtime_error("cannot find this program's path (/proc/self/exe): " + error.message());

    const pipelines::Submission submission = pipelines::submitPipeline(pipeline, options, slurm);
    std::map<std::string, const pipelines::SubmittedJob*> jobOf;
    for (const auto& job : submission.jobs) jobOf[job.stage] = &job;
    for (const pipelines::PlannedStage& p : submission.plan) {
        const std::string id = pipelines::stageId(p.kind, p.name);
        const auto job = jobOf.find(id);
        if (job == jobOf.end()) {
            status(global, "cached     " + id);
            continue;
        }
        std::string after;
        for (const std::string& a : job->second->after) after += (after.empty() ? " after " : ", ") + a;
        status(global, "submitted  " + id + " as job " + job->second->job + after + " (" + p.reason + ")");
    }
    status(global, std::to_string(submission.jobs.size()) + " of " + std::to_string(submission.plan.size()) +
                       " stages submitted; follow them with: vtex run --status " + submission.output.string());
}

void printSubmissionStatus(const std::string& folder) {
    const std::vector<pipelines::StageStatus> stages = pipelines::submissionStatus(folder);
    std::size_t width = 5;
    for (const auto& s : stages) width = std::max(width, s.stage.size());
    std::map<std::string, int> counts;
    for (const auto& s : stages) {
        const std::string state = pipelines::stateName(s.state);
        ++counts[state];
        std::cout << std::left << std::setw(int(width) + 2) << s.stage << std::setw(9) << state
                  << std::setw(10) << (s.job.empty() ? "-" : s.job) << s.detail;
        // (a job cancelled before it started has no log)
        if (s.state == pipelines::StageStatus::State::Failed && !s.log.empty() && fs::exists(s.log))
            std::cout << "; log: " << s.log.string();
        std::cout << "\n";
    }
    std::string summary;
    for (const char* state : {"cached", "done", "running", "queued", "failed", "stale"})
        if (counts.count(state)) summary += (summary.empty() ? "" : ", ") + std::to_string(counts[state]) + " " + state;
    std::cout << stages.size() << " stages: " << summary << "\n";
}

}  // namespace vtex::cli
