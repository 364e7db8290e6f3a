#include "memory_monitor.h"

#include <chrono>
#include <fstream>

#include <unistd.h>

namespace vtex::pipelines {

std::uint64_t MemoryMonitor::residentBytes() {
    std::ifstream statm("/proc/self/statm");
    std::uint64_t size = 0, resident = 0;
    if (!(statm >> size >> resident)) return 0;
    return resident * std::uint64_t(sysconf(_SC_PAGESIZE));
}

MemoryMonitor::MemoryMonitor() {
    mThread = std::thread([this] {
        std::unique_lock lock(mMutex);
        while (!mStopping) {
            lock.unlock();
            const std::uint64_t now = residentBytes();
            lock.lock();
            for (auto& [id, peak] : mPeaks) peak = std::max(peak, now);
            mWake.wait_for(lock, std::chrono::milliseconds(5));
        }
    });
}

MemoryMonitor::~MemoryMonitor() {
    {
        std::lock_guard lock(mMutex);
        mStopping = true;
    }
    mWake.notify_all();
    mThread.join();
}

std::uint64_t MemoryMonitor::start() {
    const std::uint64_t now = residentBytes();
    std::lock_guard lock(mMutex);
    mPeaks[mNextId] = now;
    return mNextId++;
}

std::uint64_t MemoryMonitor::stop(std::uint64_t id) {
    const std::uint64_t now = residentBytes();
    std::lock_guard lock(mMutex);
    const auto found = mPeaks.find(id);
    if (found == mPeaks.end()) return now;
    const std::uint64_t peak = std::max(found->second, now);
    mPeaks.erase(found);
    return peak;
}

}  // namespace vtex::pipelines
