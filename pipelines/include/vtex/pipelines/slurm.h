/// @file
/// @brief `vtex run --executor slurm`: a pipeline's stages as Slurm jobs, and their status.
///
/// Every stage that is not cached becomes one sbatch job running `vtex run PIPELINE -o OUTPUT
/// --stage KIND/NAME --wait` on the shared output folder, held back by `--dependency=afterok:`
/// on the jobs of its inputs (and cancelled by Slurm when one of them fails,
/// `--kill-on-invalid-dep=yes`); a stage whose outputs are up to date is not submitted, so
/// resubmitting after a failure, a `scancel` or a lost allocation submits only what is missing.
/// Each job runs alone what a whole local run would run in its place (RunOptions::stage), so the
/// outputs are the same bytes.
///
/// A submission leaves, under OUTPUT/slurm/: jobs.json (the pipeline, each submitted stage's job
/// id, script and log), one job script per stage (KIND.NAME.sh) and the jobs' logs
/// (logs/KIND.NAME.JOBID.log). A submission is refused while jobs of the previous one are still
/// queued or running, and so is a local `vtex run` on that folder (runPipeline).
///
/// What each stage asks for (SlurmSettings): renders and tiles the whole node (`--exclusive`,
/// `--mem=0` unless a --mem is given), samples and builds `cpus` CPUs, sources, compares and
/// assembles one, each running with as many threads as it has CPUs. docs/cluster.md.
#pragma once

#include <vtex/pipelines/pipeline.h>
#include <vtex/pipelines/run_observer.h>

#include <filesystem>
#include <string>
#include <vector>

namespace vtex::pipelines {

struct SlurmOptions {
    SlurmSettings settings;        ///< the pipeline file's [slurm], with the flags' overrides
    std::filesystem::path vtex;    ///< the program the jobs run: absolute, on the nodes' shared filesystem
};

struct SubmittedJob {
    std::string stage;             ///< "kind/name"
    std::string job;               ///< Slurm's job id
    std::vector<std::string> after;  ///< the job ids it depends on (afterok)
    std::filesystem::path script, log;
};

struct Submission {
    std::filesystem::path output, jobsFile;
    std::vector<PlannedStage> plan;  ///< every stage; those that run were submitted
    std::vector<SubmittedJob> jobs;
};

/// Submits the stages of `pipeline` that are not cached (RunOptions: output, force, waitForLock;
/// the others do not apply). Holds the output folder's lock while it submits, so that a job that
/// starts meanwhile waits. Throws vtex::IoError when the folder is in use (a local run, or jobs of
/// an earlier submission still queued or running: their ids named), std::runtime_error when
/// sbatch fails (its message; the jobs already submitted are cancelled, so a submission is whole
/// or absent), and what runPipeline throws before it starts.
Submission submitPipeline(const Pipeline& pipeline, const RunOptions& options, const SlurmOptions& slurm);

/// A stage of the last submission to a folder, as `vtex run --status` shows it.
struct StageStatus {
    enum class State {
        Cached,   ///< up to date, and not submitted (it was already)
        Queued,   ///< its job waits (dependencies, resources, held)
        Running,
        Done,     ///< its job completed
        Failed,   ///< its job failed, was cancelled or timed out, or is gone with its outputs missing
        Stale     ///< not up to date and not submitted (the pipeline or an input changed since)
    };
    std::string stage;             ///< "kind/name"
    State state = State::Stale;
    std::string job;               ///< empty when not submitted
    std::string detail;            ///< Slurm's state and reason ("PENDING, Dependency"), or why it is stale
    std::filesystem::path log;     ///< the job's log, when it has one
};

/// "cached", "queued", "running", "done", "failed" or "stale".
std::string stateName(StageStatus::State state);

/// Every stage of the pipeline last submitted to `output` (OUTPUT/slurm/jobs.json), from squeue
/// and, for jobs Slurm no longer lists, the stages' manifests. Throws vtex::InputError when the
/// folder holds no submission, std::runtime_error when squeue fails.
std::vector<StageStatus> submissionStatus(const std::filesystem::path& output);

/// The jobs of the last submission to `output` that are still queued or running; empty when
/// there are none or no submission, or when Slurm cannot be asked (no squeue on this machine).
std::vector<std::string> liveSubmissionJobs(const std::filesystem::path& output);

}  // namespace vtex::pipelines
