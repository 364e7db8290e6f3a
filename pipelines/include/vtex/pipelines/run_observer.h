/// @file
/// @brief What `vtex run` tells while it runs: the plan (which stages run and why), each stage's
/// start, own progress and end, and the time left estimated from the cache's earlier times.
///
/// The pipelines library never prints: the CLI draws these on a terminal (stages done / total,
/// the running stage's bar, the ETA) and prints the plan for `--dry-run`.
#pragma once

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace vtex::pipelines {

struct StageRecord;

/// One stage as a run plans it, before anything runs (planPipeline).
struct PlannedStage {
    std::string kind, name;
    std::size_t wave = 0;       ///< stages of one wave run side by side, waves one after another
    bool runs = false;          ///< false: its outputs are up to date and it will be cached
    /// Why it runs: "forced (--force)", "no earlier run", "changed parameter: spp 1 → 4",
    /// "changed input: scene", "missing output renders/a.png", "input render 'a' runs first"…
    std::string reason;
    /// Its work time in the earlier run its manifest records, whether or not that run is still
    /// valid (the ETA's estimate); < 0: no earlier run.
    double earlierSeconds = -1;
};

/// Receives a run's events. Called from the stages' worker threads: implementations must be
/// thread-safe. `index` is the stage's position in the plan.
class RunObserver {
public:
    virtual ~RunObserver() = default;
    /// Before the first stage.
    virtual void planned(const std::vector<PlannedStage>& plan) = 0;
    /// A stage starts its work (not called for cached or skipped stages).
    virtual void started(std::size_t index) = 0;
    /// The running stage's own progress, a fraction from 0 to 1 of its current phase.
    virtual void progressed(std::size_t index, double fraction) = 0;
    /// A stage is over: ran, cached, failed or skipped.
    virtual void finished(std::size_t index, const StageRecord& record) = 0;
};

/// One stage's timing as the ETA sees it.
struct StageTiming {
    enum class State { Pending, Running, Done } state = State::Pending;
    std::size_t wave = 0;
    double expectedSeconds = -1;  ///< what the cache recorded for it; < 0: unknown
    double elapsedSeconds = 0;    ///< a running stage's time so far
    double fraction = -1;         ///< a running stage's own progress (0 to 1); < 0: unknown
};

/// Seconds until the last stage is done. Waves run one after another and the stages of a wave
/// side by side on `jobs` slots (≥ 1): a wave takes the larger of its longest stage and its total
/// over `jobs`. A pending stage takes its expected time; a running one what its own progress
/// says (elapsed · (1 − f) / f), else its expected time less its elapsed time (at least 0).
/// nullopt when a stage still to do has neither (nothing to estimate from).
std::optional<double> estimateRemainingSeconds(const std::vector<StageTiming>& stages, int jobs);

}  // namespace vtex::pipelines
