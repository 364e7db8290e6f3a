// submissionStatus: each stage of the last submission to a folder, from Slurm's view of its job
// and the cache's view of its outputs (slurm.h).
#include <vtex/pipelines/slurm.h>

#include <vtex/core/error.h>

#include "slurm_jobs.h"

#include <map>
#include <set>

namespace vtex::pipelines {
namespace {

using State = StageStatus::State;

// Slurm's job state → the stage's. Pending covers held and dependency-blocked jobs; every ended
// state other than COMPLETED is a failure (its log says which).
State stateOfJob(const std::string& slurmState) {
    if (slurmState == "COMPLETED") return State::Done;
    if (slurmState == "RUNNING" || slurmState == "COMPLETING" || slurmState == "STAGE_OUT" || slurmState == "SIGNALING" ||
        slurmState == "RESIZING")
        return State::Running;
    if (detail::isLive(slurmState)) return State::Queued;
    return State::Failed;
}

}  // namespace

std::string stateName(State state) {
    switch (state) {
        case State::Cached: return "cached";
        case State::Queued: return "queued";
        case State::Running: return "running";
        case State::Done: return "done";
        case State::Failed: return "failed";
        case State::Stale: return "stale";
    }
    return "?";
}

std::vector<StageStatus> submissionStatus(const std::filesystem::path& output) {
    const auto record = detail::readJobsRecord(output);
    if (!record) throw InputError(output, "no Slurm submission here (no slurm/jobs.json): run vtex run --executor slurm first");
    // The cache's view: what is up to date now (read only; the jobs may be writing meanwhile, and a
    // stage whose manifest is not written yet is simply not up to date).
    RunOptions options;
    options.output = output;  // where it is now, should the folder have moved
    const std::vector<PlannedStage> plan = planPipeline(loadPipeline(record->pipeline), options);
    std::map<std::string, const SubmittedJob*> jobOf;
    std::vector<std::string> ids;
    for (const SubmittedJob& j : record->jobs) {
        jobOf[j.stage] = &j;
        ids.push_back(j.job);
    }
    const std::map<std::string, detail::JobState> slurm = detail::queryJobs(ids);

    std::vector<StageStatus> out;
    for (const PlannedStage& p : plan) {
        StageStatus s;
        s.stage = stageId(p.kind, p.name);
        const auto submitted = jobOf.find(s.stage);
        if (submitted == jobOf.end()) {
            s.state = p.runs ? State::Stale : State::Cached;
            if (p.runs) s.detail = p.reason;
            out.push_back(s);
            continue;
        }
        s.job = submitted->second->job;
        s.log = submitted->second->log;
        if (const auto known = slurm.find(s.job); known != slurm.end()) {
            s.state = stateOfJob(known->second.state);
            s.detail = known->second.state + (known->second.reason == "None" ? "" : ", " + known->second.reason);
        } else {
            // Slurm has forgotten the job (MinJobAge): its outputs tell whether it did its work.
            s.state = p.runs ? State::Failed : State::Done;
            s.detail = p.runs ? "no longer known to Slurm, and not in the cache (" + p.reason + ")" : "no longer known to Slurm";
        }
        out.push_back(s);
    }
    return out;
}

}  // namespace vtex::pipelines
