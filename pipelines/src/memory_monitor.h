// Resident memory while stages run: a thread samples the process's resident set every few
// milliseconds and keeps, for each stage being watched, the largest value seen. Stages of one
// wave run side by side in this process, so a stage's figure is the process peak while it ran:
// its own peak, plus what ran beside it.
#pragma once

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <thread>

namespace vtex::pipelines {

class MemoryMonitor {
public:
    MemoryMonitor();
    ~MemoryMonitor();
    MemoryMonitor(const MemoryMonitor&) = delete;
    MemoryMonitor& operator=(const MemoryMonitor&) = delete;

    /// Starts watching; the id is for stop().
    std::uint64_t start();
    /// The largest resident set (bytes) seen since start(id), this moment included.
    std::uint64_t stop(std::uint64_t id);

    /// The resident set of this process now (bytes); 0 where /proc is not readable.
    static std::uint64_t residentBytes();

private:
    std::mutex mMutex;
    std::condition_variable mWake;
    bool mStopping = false;
    std::uint64_t mNextId = 0;
    std::map<std::uint64_t, std::uint64_t> mPeaks;  // id → peak so far
    std::thread mThread;
};

}  // namespace vtex::pipelines
