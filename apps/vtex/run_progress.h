// `vtex run` and `vtex demo` on a terminal: one status line under the log, redrawn five times a
// second — stages done / total, the running stage's own bar (or a spinner and its elapsed time
// when it reports none), how many run beside it, and the time left from the cache's earlier times
// (pipelines::estimateRemainingSeconds). Off the terminal (or with --quiet) nothing is drawn and
// the log stays as it is.
#pragma once

#include "cli.h"

#include <vtex/pipelines/run_observer.h>

#include <chrono>
#include <condition_variable>
#include <mutex>
#include <thread>
#include <vector>

namespace vtex::cli {

class RunProgressDisplay final : public pipelines::RunObserver {
public:
    /// `jobs`: the stages a wave runs at once (0: as many as cores).
    RunProgressDisplay(const GlobalOptions& options, int jobs);
    ~RunProgressDisplay() override;
    RunProgressDisplay(const RunProgressDisplay&) = delete;
    RunProgressDisplay& operator=(const RunProgressDisplay&) = delete;

    /// Whether it draws (stderr is a terminal and the user did not ask for --quiet).
    bool enabled() const { return mEnabled; }
    /// The run's log: each line printed above the status line (status() when not drawing).
    std::function<void(const std::string&)> logger();

    void planned(const std::vector<pipelines::PlannedStage>& plan) override;
    void started(std::size_t index) override;
    void progressed(std::size_t index, double fraction) override;
    void finished(std::size_t index, const pipelines::StageRecord& record) override;

private:
    void tick();
    std::string line() const;  // with mMutex held
    void clear();              // with mMutex held

    const GlobalOptions& mOptions;
    const bool mEnabled;
    const int mJobs;
    mutable std::mutex mMutex;
    std::vector<pipelines::PlannedStage> mPlan;
    std::vector<pipelines::StageTiming> mTimings;
    std::vector<std::chrono::steady_clock::time_point> mStarts;
    std::size_t mDone = 0;
    bool mDrawn = false, mStop = false;
    unsigned mFrame = 0;
    std::condition_variable mWake;
    std::thread mTicker;
};

}  // namespace vtex::cli
