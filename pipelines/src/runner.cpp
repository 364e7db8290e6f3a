// Runs a Pipeline's stage graph (stage_graph.h): stages in waves (sources, samples, builds,
// renders, compares), the stages of a wave in parallel, each skipped when its manifest says its
// outputs are up to date; or, for a dry run, only tells which would run and why.
#include <vtex/pipelines/pipeline.h>
#include <vtex/pipelines/run_observer.h>
#include <vtex/pipelines/slurm.h>

#include <vtex/core/atomic_file.h>
#include <vtex/core/error.h>
#include <vtex/core/folder_lock.h>
#include <vtex/core/memory_budget.h>
#include <vtex/core/version.h>

#include "content_hash.h"
#include "memory_monitor.h"
#include "report.h"
#include "slurm_jobs.h"
#include "stage_graph.h"

#include <nlohmann/json.hpp>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <chrono>
#include <fstream>
#include <mutex>
#include <sstream>

namespace vtex::pipelines {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;
using Status = StageRecord::Status;
using detail::Stage;

std::vector<std::string> lines(const std::string& text) {
    std::vector<std::string> out;
    std::istringstream in(text);
    for (std::string line; std::getline(in, line);) out.push_back(line);
    return out;
}

std::vector<std::string> words(const std::string& line) {
    std::vector<std::string> out;
    std::istringstream in(line);
    for (std::string word; in >> word;) out.push_back(word);
    return out;
}

bool isHash(const std::string& word) {
    return word.size() == 32 && word.find_first_not_of("0123456789abcdef") == std::string::npos;
}

// What changed between the description an earlier run recorded and this run's: the first line
// that differs, and in it the first word. A content hash that changed is an input, named by the
// word before it ("mesh", "scene", "octree", "file"); another word is a parameter's value, named
// likewise ("spp 1 → 4").
std::string describeChange(const std::string& before, const std::string& now) {
    const std::vector<std::string> a = lines(before), b = lines(now);
    for (std::size_t i = 0; i < std::min(a.size(), b.size()); ++i) {
        if (a[i] == b[i]) continue;
        if (i == 0) return "made by another vtex (" + a[i] + ")";
        const std::vector<std::string> x = words(a[i]), y = words(b[i]);
        for (std::size_t w = 0; w < std::min(x.size(), y.size()); ++w) {
            if (x[w] == y[w]) continue;
            // "file <hash> up z": the input is named by the word before its hash.
            if (isHash(y[w])) return "changed input: " + (w > 0 ? y[w - 1] : std::string("content"));
            return "changed parameter: " + (w > 0 ? y[w - 1] + " " : "") + x[w] + " → " + y[w];
        }
        return "changed parameters: " + a[i] + " → " + b[i];
    }
    return "changed inputs (" + std::to_string(a.size()) + " lines of inputs and parameters, now " +
           std::to_string(b.size()) + ")";
}

// Why `stage`, whose key is set, must run: "" when its manifest's key matches and every output
// still has the recorded content (then its output hashes and details are filled in from it).
std::string staleReason(Stage& stage, const fs::path& root, const std::string& description) {
    const fs::path manifest = detail::manifestPath(stage, root);
    std::ifstream in(manifest);
    if (!in) return "no earlier run";
    try {
        const Json j = Json::parse(in);
        if (j.at("key").get<std::string>() != stage.record.key)
            return j.contains("description") ? describeChange(j["description"].get<std::string>(), description)
                                             : "changed parameters or inputs";
        std::map<std::string, std::string> hashes;
        for (const auto& [role, path] : stage.outputs) {
            const std::string recorded = j.at("outputs").at(role).at("hash").get<std::string>();
            const std::string name = path.lexically_relative(root).generic_string();
            if (!fs::is_regular_file(path)) return "missing output " + name;
            if (hashFile(path) != recorded) return "output " + name + " changed since it was made";
            hashes[role] = recorded;
        }
        stage.outputHashes = hashes;
        stage.record.detailsJson = j.value("details", Json::object()).dump();
    } catch (const std::exception&) {
        return "its manifest is unreadable";  // unreadable or foreign: redo the stage
    }
    return "";
}

// The work time the stage's manifest records, valid or not: what the ETA expects of it.
double earlierSeconds(const Stage& stage, const fs::path& root) {
    std::ifstream in(detail::manifestPath(stage, root));
    if (!in) return -1;
    try {
        return Json::parse(in).value("seconds", -1.0);
    } catch (const std::exception&) {
        return -1;
    }
}

void writeManifest(const Stage& stage, const fs::path& root, const Json& details, const std::string& description) {
    Json outputs = Json::object();
    for (const auto& [role, path] : stage.outputs)
        outputs[role] = {{"file", path.filename().string()}, {"hash", stage.outputHashes.at(role)}};
    const Json manifest = {{"kind", stage.kind},       {"name", stage.name},   {"key", stage.record.key},
                           {"vtex_version", kVersion}, {"outputs", outputs},   {"seconds", stage.record.seconds},
                           {"details", details},       {"description", description}};
    writeFileAtomically(detail::manifestPath(stage, root), manifest.dump(2) + "\n");
}

fs::path outputRoot(const Pipeline& pipeline, const RunOptions& options) {
    return options.output.empty() ? pipeline.output : options.output;
}

}  // namespace

std::vector<PlannedStage> detail::planStages(std::vector<Stage>& stages, const fs::path& root, bool force) {
    std::vector<PlannedStage> out;
    std::size_t wave = 0;
    for (std::size_t i = 0; i < stages.size(); ++i) {
        Stage& stage = stages[i];
        if (i > 0 && stage.kind != stages[i - 1].kind) ++wave;
        PlannedStage p{stage.kind, stage.name, wave, true, "", earlierSeconds(stage, root)};
        if (force) p.reason = "forced (--force)";
        for (std::size_t input : stage.inputs)
            if (out[input].runs && p.reason.empty()) p.reason = "input " + stages[input].kind + " '" + stages[input].name + "' runs first";
        if (p.reason.empty()) {
            try {
                const std::string description = stage.describe(stages);
                stage.record.key = hashBytes(description);
                p.reason = staleReason(stage, root, description);
                p.runs = !p.reason.empty();
            } catch (const std::exception& e) {
                p.reason = std::string("cannot read its inputs: ") + e.what();
            }
        }
        out.push_back(p);
    }
    // The plan leaves no trace: the graph is run from scratch.
    for (Stage& stage : stages) {
        stage.outputHashes.clear();
        stage.record = StageRecord{};
    }
    return out;
}

namespace {

// Forwards a stage's own progress to the run's observer, as the fraction of its current phase.
class StageProgress final : public Progress {
public:
    StageProgress(RunObserver* observer, std::size_t index) : mObserver(observer), mIndex(index) {}
    void start(std::string_view, std::uint64_t total) override {
        mTotal = total;
        mDone = 0;
        if (mObserver) mObserver->progressed(mIndex, 0);
    }
    void advance(std::uint64_t units) override {
        const std::uint64_t done = mDone.fetch_add(units, std::memory_order_relaxed) + units;
        if (mObserver && mTotal > 0) mObserver->progressed(mIndex, std::min(1.0, double(done) / double(mTotal)));
    }
    void finish() override {}

private:
    RunObserver* mObserver;
    std::size_t mIndex;
    std::uint64_t mTotal = 0;
    std::atomic<std::uint64_t> mDone{0};
};


}  // namespace

// (stage_graph.h) With the folder's lock held: the stages' folders, cleared of a killed run's temporaries when
// the lock is this run's alone (`removeTemporaries`; a stage run alone shares it with the other
// stages of its submission, whose temporaries are theirs).
// (stage_graph.h) Called once the pipeline is accepted whole: a refused one (exit 3) left an
// empty output directory tree behind (found by fuzz_cli.py).
void detail::createFolder(const fs::path& folder) {
    std::error_code error;
    fs::create_directories(folder, error);
    if (error) throw IoError(folder, "cannot create the output directory: " + error.message());
}

void detail::prepareFolders(const fs::path& root, bool removeTemporaries) {
    for (const char* folder : {"", "sources", "samples", "builds", "tiles", "renders", "compares"}) {
        detail::createFolder(root / folder);
        if (!removeTemporaries) continue;
        // A killed run leaves the hidden temporaries of AtomicOutputFile behind; holding the
        // folder's lock, this run knows no other run writes them, so they can go.
        std::error_code error;
        for (const auto& entry : fs::directory_iterator(root / folder, error)) {
            const std::string file = entry.path().filename().string();
            if (file.front() == '.' && file.find(".tmp.") != std::string::npos) fs::remove(entry.path(), error);
        }
    }
}

std::string statusName(StageRecord::Status status) {
    switch (status) {
        case Status::Ran: return "ran";
        case Status::Cached: return "cached";
        case Status::Failed: return "failed";
        case Status::Skipped: return "skipped";
    }
    return "?";
}

bool RunReport::succeeded() const {
    for (const auto& s : stages)
        if (s.status == Status::Failed || s.status == Status::Skipped) return false;
    return true;
}

std::vector<PlannedStage> planPipeline(const Pipeline& pipeline, const RunOptions& options) {
    const fs::path root = outputRoot(pipeline, options);
    checkOutputFolder(root, {pipeline.file});
    MemoryBudget budget(options.maxMemoryBytes);
    std::vector<Stage> stages;
    std::vector<Omission> leftOut;
    detail::buildStageGraph(pipeline, root, options.force, budget, stages, leftOut);
    return detail::planStages(stages, root, options.force);
}

namespace {

// Runs one stage (its inputs done): skipped after a failed input, cached when up to date, else
// run, its outputs hashed and its manifest written. Never throws: a failure is its record's.
void runStage(std::vector<Stage>& stages, std::size_t i, const fs::path& root, const RunOptions& options,
              MemoryMonitor& memory, const std::function<void(const std::string&)>& log) {
    Stage& stage = stages[i];
    stage.record.kind = stage.kind;
    stage.record.name = stage.name;
    for (const auto& [role, path] : stage.outputs) stage.record.outputs.push_back(path);
    for (std::size_t input : stage.inputs) {
        const Status upstream = stages[input].record.status;
        if (upstream == Status::Failed || upstream == Status::Skipped) {
            stage.record.status = Status::Skipped;
            stage.record.message = "not run: " + stages[input].kind + " '" + stages[input].name + "' " + statusName(upstream);
            log("skipped " + stage.kind + " " + stage.name + " (" + stage.record.message + ")");
            return;
        }
    }
    try {
        const std::string description = stage.describe(stages);
        stage.record.key = hashBytes(description);
        const std::string why = options.force ? "forced (--force)" : staleReason(stage, root, description);
        if (why.empty()) {
            stage.record.status = Status::Cached;
            log("cached  " + stage.kind + " " + stage.name);
            return;
        }
        log("run     " + stage.kind + " " + stage.name + " (" + why + ")");
        if (options.observer) options.observer->started(i);
        StageProgress progress(options.observer, i);
        stage.progress = &progress;
        const auto t = std::chrono::steady_clock::now();
        const std::uint64_t watch = memory.start();
        Json details;
        try {
            details = stage.run(stages);
        } catch (...) {
            memory.stop(watch);
            throw;
        }
        stage.record.peakMemoryBytes = memory.stop(watch);
        stage.record.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t).count();
        for (const auto& [role, path] : stage.outputs) stage.outputHashes[role] = hashFile(path);
        writeManifest(stage, root, details, description);
        stage.record.detailsJson = details.dump();
        stage.record.status = Status::Ran;
        char took[64];
        std::snprintf(took, sizeof took, " in %.2f s, peak %s", stage.record.seconds,
                      formatBytes(stage.record.peakMemoryBytes).c_str());
        log("ran     " + stage.kind + " " + stage.name + took);
    } catch (const std::exception& e) {
        stage.record.status = Status::Failed;
        stage.record.message = e.what();
        stage.record.badInput = dynamic_cast<const InputError*>(&e) != nullptr;
        log("failed  " + stage.kind + " " + stage.name + ": " + e.what());
    }
}

// RunOptions::stage: the stage it names.
std::size_t findStage(const std::vector<Stage>& stages, const std::string& id) {
    std::string known;
    for (std::size_t i = 0; i < stages.size(); ++i) {
        const std::string each = stageId(stages[i].kind, stages[i].name);
        if (each == id) return i;
        known += (known.empty() ? "" : ", ") + each;
    }
    throw UnknownStage("no stage '" + id + "' in the pipeline (its stages: " + known + ")");
}

// Before `target` runs alone: every stage it depends on, directly or not, must be up to date in
// the cache, as a whole run would find it. Their output hashes, which the target's key includes,
// are read from their manifests; the first that is not throws vtex::InputError naming it.
void takeInputsFromCache(std::vector<Stage>& stages, std::size_t target, const fs::path& root, const fs::path& file) {
    std::vector<bool> needed(stages.size(), false);
    needed[target] = true;
    for (std::size_t j = target + 1; j-- > 0;)  // a stage's inputs come before it (waves)
        if (needed[j])
            for (std::size_t input : stages[j].inputs) needed[input] = true;
    for (std::size_t i = 0; i < target; ++i) {
        if (!needed[i]) continue;
        Stage& stage = stages[i];
        const std::string description = stage.describe(stages);
        stage.record.key = hashBytes(description);
        const std::string why = staleReason(stage, root, description);
        if (!why.empty())
            throw InputError(file, "stage '" + stageId(stage.kind, stage.name) + "', an input of '" +
                                       stageId(stages[target].kind, stages[target].name) + "', is not in the cache (" +
                                       why + "): run it first, or the whole pipeline");
        stage.record.status = Status::Cached;
    }
}

}  // namespace

RunReport runPipeline(const Pipeline& pipeline, const RunOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const fs::path root = outputRoot(pipeline, options);
    // Before anything: `-o` a FIFO, a device, a file or the pipeline itself is bad input.
    checkOutputFolder(root, {pipeline.file});
    std::mutex logMutex;
    auto log = [&](const std::string& line) {
        std::lock_guard lock(logMutex);
        if (options.log) options.log(line);
    };

    RunReport report;
    report.output = root;
    // One memory limit for the stages that run side by side: each reserves its estimate before
    // its work and waits while the others leave too little (memory_budget.h).
    MemoryBudget budget(options.maxMemoryBytes);
    std::vector<Stage> stages;
    detail::buildStageGraph(pipeline, root, options.force, budget, stages, report.leftOut);
    const std::size_t alone = options.stage.empty() ? stages.size() : findStage(stages, options.stage);

    detail::createFolder(root);
    // One run per output folder (folder_lock.h), held until this run returns; a stage alone
    // shares it with the other stages of a cluster submission and holds its own stage's.
    const FolderLock::Mode mode = options.waitForLock ? FolderLock::Mode::Wait : FolderLock::Mode::Refuse;
    const FolderLock lock(root, mode, alone < stages.size() ? FolderLock::Access::Shared : FolderLock::Access::Exclusive);
    // The jobs of a Slurm submission write this folder without holding its lock while they pend.
    if (alone == stages.size()) detail::refuseWhileJobsLive(root, liveSubmissionJobs(root));
    detail::prepareFolders(root, alone == stages.size());
    MemoryMonitor memory;
    if (alone < stages.size()) {
        const Stage& stage = stages[alone];
        const FolderLock stageLock(root / (stage.kind + "s"), mode, FolderLock::Access::Exclusive, "." + stage.name + ".lock");
        takeInputsFromCache(stages, alone, root, pipeline.file);
        runStage(stages, alone, root, options, memory, log);
        report.stages.push_back(stages[alone].record);
        report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        return report;
    }
    // The plan for the progress display, made under the lock (no other run changes the cache).
    if (options.observer) options.observer->planned(detail::planStages(stages, root, options.force));

    // Run wave by wave; a wave is a run of stages of one kind.
    tbb::task_arena arena(options.jobs > 0 ? options.jobs : tbb::task_arena::automatic);
    std::size_t first = 0;
    while (first < stages.size()) {
        std::size_t last = first;
        while (last < stages.size() && stages[last].kind == stages[first].kind) ++last;
        arena.execute([&] {
            tbb::parallel_for(first, last, [&](std::size_t i) {
                runStage(stages, i, root, options, memory, log);
                if (options.observer) options.observer->finished(i, stages[i].record);
            });
        });
        first = last;
    }

    for (const Stage& s : stages) report.stages.push_back(s.record);
    report.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    writeReports(pipeline, report);
    return report;
}

}  // namespace vtex::pipelines
