#include "run_progress.h"

#include <vtex/pipelines/pipeline.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <iostream>

#include <sys/ioctl.h>
#include <unistd.h>

namespace vtex::cli {
namespace {

using State = pipelines::StageTiming::State;

std::string clock(double seconds) {
    char text[32];
    const long s = std::lround(std::max(0.0, seconds));
    if (s >= 3600) std::snprintf(text, sizeof text, "%ld:%02ld:%02ld", s / 3600, s / 60 % 60, s % 60);
    else std::snprintf(text, sizeof text, "%ld:%02ld", s / 60, s % 60);
    return text;
}

std::size_t terminalWidth() {
    winsize size{};
    if (::ioctl(STDERR_FILENO, TIOCGWINSZ, &size) == 0 && size.ws_col > 20) return size.ws_col;
    return 100;
}

}  // namespace

RunProgressDisplay::RunProgressDisplay(const GlobalOptions& options, int jobs)
    : mOptions(options),
      mEnabled(options.verbosity() != Verbosity::Quiet && ::isatty(STDERR_FILENO) == 1),
      mJobs(jobs > 0 ? jobs : int(std::max(1u, std::thread::hardware_concurrency()))) {
    if (mEnabled) mTicker = std::thread([this] { tick(); });
}

RunProgressDisplay::~RunProgressDisplay() {
    if (!mEnabled) return;
    {
        std::lock_guard lock(mMutex);
        mStop = true;
        clear();
    }
    mWake.notify_all();
    mTicker.join();
}

std::function<void(const std::string&)> RunProgressDisplay::logger() {
    return [this](const std::string& text) {
        if (!mEnabled) return status(mOptions, text);
        std::lock_guard lock(mMutex);
        clear();
        std::fprintf(stderr, "%s\n", text.c_str());
        std::fflush(stderr);
    };
}

void RunProgressDisplay::planned(const std::vector<pipelines::PlannedStage>& plan) {
    std::lock_guard lock(mMutex);
    mPlan = plan;
    mTimings.assign(plan.size(), {});
    mStarts.assign(plan.size(), {});
    for (std::size_t i = 0; i < plan.size(); ++i) {
        mTimings[i].wave = plan[i].wave;
        // A stage the plan finds up to date costs nothing; one without an earlier time is unknown.
        mTimings[i].expectedSeconds = plan[i].runs ? plan[i].earlierSeconds : 0.0;
    }
}

void RunProgressDisplay::started(std::size_t index) {
    std::lock_guard lock(mMutex);
    if (index >= mTimings.size()) return;
    mTimings[index].state = State::Running;
    mStarts[index] = std::chrono::steady_clock::now();
}

void RunProgressDisplay::progressed(std::size_t index, double fraction) {
    std::lock_guard lock(mMutex);
    if (index < mTimings.size()) mTimings[index].fraction = fraction;
}

void RunProgressDisplay::finished(std::size_t index, const pipelines::StageRecord&) {
    std::lock_guard lock(mMutex);
    if (index >= mTimings.size() || mTimings[index].state == State::Done) return;
    mTimings[index].state = State::Done;
    ++mDone;
}

void RunProgressDisplay::clear() {
    if (!mDrawn) return;
    std::fputs("\r\033[K", stderr);
    mDrawn = false;
}

// "[12/70] render fig7 [=====     ]  45%  0:03  +2 running  ETA 1:05"
std::string RunProgressDisplay::line() const {
    const auto now = std::chrono::steady_clock::now();
    std::vector<pipelines::StageTiming> timings = mTimings;
    std::size_t shown = timings.size(), running = 0;
    for (std::size_t i = 0; i < timings.size(); ++i) {
        if (timings[i].state != State::Running) continue;
        timings[i].elapsedSeconds = std::chrono::duration<double>(now - mStarts[i]).count();
        if (running++ == 0) shown = i;
    }
    std::string text = "[" + std::to_string(mDone) + "/" + std::to_string(timings.size()) + "]";
    if (shown < timings.size()) {
        text += " " + mPlan[shown].kind + " " + mPlan[shown].name + " ";
        const pipelines::StageTiming& s = timings[shown];
        if (s.fraction >= 0) {
            constexpr int kWidth = 20;
            const int filled = int(std::clamp(s.fraction, 0.0, 1.0) * kWidth);
            char percent[16];
            std::snprintf(percent, sizeof percent, " %3d%%", int(100 * std::clamp(s.fraction, 0.0, 1.0)));
            text += "[" + std::string(std::size_t(filled), '=') + std::string(std::size_t(kWidth - filled), ' ') + "]" + percent;
        } else {
            text += std::string(1, "|/-\\"[mFrame % 4]);
        }
        text += "  " + clock(s.elapsedSeconds);
        if (running > 1) text += "  +" + std::to_string(running - 1) + " running";
    }
    const auto eta = pipelines::estimateRemainingSeconds(timings, mJobs);
    text += eta ? "  ETA " + clock(*eta) : "  ETA unknown (no earlier run)";
    return text.substr(0, terminalWidth() - 1);
}

void RunProgressDisplay::tick() {
    std::unique_lock lock(mMutex);
    while (!mStop) {
        mWake.wait_for(lock, std::chrono::milliseconds(200));
        if (mStop || mPlan.empty()) continue;
        ++mFrame;
        std::fprintf(stderr, "\r\033[K%s", line().c_str());
        std::fflush(stderr);
        mDrawn = true;
    }
}

}  // namespace vtex::cli
