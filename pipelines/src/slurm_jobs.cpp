#include "slurm_jobs.h"

#include "subprocess.h"

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>

#include <nlohmann/json.hpp>

#include <fstream>
#include <set>
#include <sstream>
#include <stdexcept>

namespace vtex::pipelines::detail {

namespace fs = std::filesystem;
using Json = nlohmann::json;

fs::path slurmFolder(const fs::path& output) { return output / "slurm"; }
fs::path jobsFile(const fs::path& output) { return slurmFolder(output) / "jobs.json"; }

void writeJobsRecord(const JobsRecord& record) {
    Json jobs = Json::array();
    for (const SubmittedJob& j : record.jobs)
        jobs.push_back({{"stage", j.stage}, {"job", j.job}, {"after", j.after}, {"script", j.script.string()}, {"log", j.log.string()}});
    const Json j = {{"pipeline", record.pipeline.string()},
                    {"output", record.output.string()},
                    {"submitted_at", record.submittedAt},
                    {"jobs", jobs}};
    writeFileAtomically(jobsFile(record.output), j.dump(2) + "\n");
}

std::optional<JobsRecord> readJobsRecord(const fs::path& output) {
    const fs::path file = jobsFile(output);
    std::ifstream in(file);
    if (!in) return std::nullopt;
    try {
        const Json j = Json::parse(in);
        JobsRecord record;
        record.pipeline = j.at("pipeline").get<std::string>();
        record.output = j.at("output").get<std::string>();
        record.submittedAt = j.value("submitted_at", std::string());
        for (const Json& job : j.at("jobs"))
            record.jobs.push_back({job.at("stage").get<std::string>(), job.at("job").get<std::string>(),
                                   job.value("after", std::vector<std::string>{}), job.value("script", std::string()),
                                   job.value("log", std::string())});
        return record;
    } catch (const std::exception& e) {
        throw InputError(file, std::string("not a vtex submission record: ") + e.what());
    }
}

std::map<std::string, JobState> queryJobs(const std::vector<std::string>& jobs) {
    std::map<std::string, JobState> states;
    if (jobs.empty()) return states;
    std::string list;
    for (const std::string& job : jobs) list += (list.empty() ? "" : ",") + job;
    // -t all: finished jobs too, for as long as the controller keeps them (MinJobAge).
    const ProcessResult r = runProcess({"squeue", "-h", "-t", "all", "-j", list, "-o", "%i|%T|%r"}, 60);
    if (r.timedOut) throw std::runtime_error("squeue did not answer in 60 s (is slurmctld up?)");
    if (r.exitStatus != 0) {
        // When none of the ids is known any more, squeue fails with this; that is an answer.
        if (r.err.find("Invalid job id") != std::string::npos) return states;
        throw std::runtime_error("squeue failed: " + (r.err.empty() ? r.out : r.err));
    }
    const std::set<std::string> asked(jobs.begin(), jobs.end());
    std::istringstream in(r.out);
    for (std::string line; std::getline(in, line);) {
        const std::size_t a = line.find('|'), b = line.find('|', a + 1);
        if (a == std::string::npos || b == std::string::npos) continue;
        const std::string id = line.substr(0, a);
        if (asked.count(id)) states[id] = {line.substr(a + 1, b - a - 1), line.substr(b + 1)};
    }
    return states;
}

bool isLive(const std::string& state) {
    static const std::set<std::string> ended = {"COMPLETED", "FAILED",    "CANCELLED", "TIMEOUT",     "NODE_FAIL",
                                                "PREEMPTED", "BOOT_FAIL", "DEADLINE",  "OUT_OF_MEMORY", "SPECIAL_EXIT",
                                                "REVOKED"};
    return !ended.count(state);
}

std::vector<std::string> liveJobs(const JobsRecord& record) {
    std::vector<std::string> ids, live;
    for (const SubmittedJob& j : record.jobs) ids.push_back(j.job);
    const auto states = queryJobs(ids);
    for (const std::string& id : ids)
        if (const auto known = states.find(id); known != states.end() && isLive(known->second.state)) live.push_back(id);
    return live;
}

void refuseWhileJobsLive(const fs::path& output, const std::vector<std::string>& live) {
    if (live.empty()) return;
    std::string ids;
    for (const std::string& id : live) ids += (ids.empty() ? "" : ", ") + id;
    throw IoError(output, "jobs of a Slurm submission to it are still queued or running (" + ids +
                              "): wait for them (vtex run --status " + output.string() + "), or scancel them");
}

}  // namespace vtex::pipelines::detail

namespace vtex::pipelines {

std::vector<std::string> liveSubmissionJobs(const std::filesystem::path& output) {
    try {
        const auto record = detail::readJobsRecord(output);
        return record ? detail::liveJobs(*record) : std::vector<std::string>{};
    } catch (const std::exception&) {
        // No Slurm to ask here (or no readable record): nothing known to run for this folder.
        return {};
    }
}

}  // namespace vtex::pipelines
