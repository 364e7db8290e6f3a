// The record a Slurm submission leaves (OUTPUT/slurm/jobs.json) and what Slurm says of its jobs:
// shared by the submission (which refuses while the last one lives), the status and a local run.
#pragma once

#include <vtex/pipelines/slurm.h>

#include <filesystem>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace vtex::pipelines::detail {

/// OUTPUT/slurm/jobs.json as the submission wrote it.
struct JobsRecord {
    std::filesystem::path pipeline, output;
    std::string submittedAt;  ///< UTC, ISO 8601
    std::vector<SubmittedJob> jobs;
};

std::filesystem::path slurmFolder(const std::filesystem::path& output);
std::filesystem::path jobsFile(const std::filesystem::path& output);

/// Writes the record atomically.
void writeJobsRecord(const JobsRecord& record);
/// The folder's record; nullopt when it has none. Throws vtex::InputError when it is unreadable.
std::optional<JobsRecord> readJobsRecord(const std::filesystem::path& output);

/// What squeue says of one job.
struct JobState {
    std::string state;   ///< PENDING, RUNNING, COMPLETED, FAILED, CANCELLED…
    std::string reason;  ///< why it pends or ended ("Dependency", "JobHeldUser", "None")
};

/// squeue's answer for `jobs` (finished ones too, as long as Slurm keeps them: MinJobAge); a job
/// it no longer knows is absent. Throws std::runtime_error when squeue cannot run or fails.
std::map<std::string, JobState> queryJobs(const std::vector<std::string>& jobs);

/// A state in which the job may still run (PENDING, RUNNING, SUSPENDED, COMPLETING…).
bool isLive(const std::string& state);

/// The record's jobs that Slurm says may still run, in the order they were submitted. Throws as
/// queryJobs does.
std::vector<std::string> liveJobs(const JobsRecord& record);

/// Throws vtex::IoError when `live` is not empty: jobs of a submission to `output` may still
/// write it, so neither a local run nor another submission may.
void refuseWhileJobsLive(const std::filesystem::path& output, const std::vector<std::string>& live);

}  // namespace vtex::pipelines::detail
