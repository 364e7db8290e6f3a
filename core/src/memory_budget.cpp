#include <vtex/core/memory_budget.h>

#include <cstdio>
#include <utility>

#include <unistd.h>

namespace vtex {

std::uint64_t defaultMemoryLimit() {
    const long pages = ::sysconf(_SC_PHYS_PAGES), size = ::sysconf(_SC_PAGESIZE);
    if (pages <= 0 || size <= 0) return 0;  // unknown: no limit
    return std::uint64_t(pages) * std::uint64_t(size) / 2;
}

std::string formatBytes(std::uint64_t bytes) {
    char text[64];
    const double b = double(bytes);
    if (b >= double(1ull << 30)) std::snprintf(text, sizeof text, "%.1f GiB", b / double(1ull << 30));
    else if (b >= double(1ull << 20)) std::snprintf(text, sizeof text, "%.0f MiB", b / double(1ull << 20));
    else if (b >= 1024.0) std::snprintf(text, sizeof text, "%.0f KiB", b / 1024.0);
    else std::snprintf(text, sizeof text, "%llu B", (unsigned long long)bytes);  // `--max-memory 1` was "0 KiB"
    return text;
}

MemoryLimitError::MemoryLimitError(const std::filesystem::path& file, const std::string& work, std::uint64_t estimate,
                                   std::uint64_t limit)
    : InputError(file, work + " needs about " + formatBytes(estimate) + ", more than the limit of " + formatBytes(limit) +
                           " (--max-memory; by default half of this machine's memory)"),
      mEstimate(estimate),
      mLimit(limit) {}

void checkMemoryEstimate(const std::filesystem::path& file, const std::string& work, std::uint64_t estimate,
                         std::uint64_t limit) {
    if (limit > 0 && estimate > limit) throw MemoryLimitError(file, work, estimate, limit);
}

MemoryBudget::Reservation MemoryBudget::reserve(const std::filesystem::path& file, const std::string& work,
                                                std::uint64_t estimate) {
    if (mLimit == 0) return {};
    checkMemoryEstimate(file, work, estimate, mLimit);
    std::unique_lock lock(mMutex);
    mFreed.wait(lock, [&] { return estimate <= mLimit - mHeld; });
    mHeld += estimate;
    return Reservation(this, estimate);
}

void MemoryBudget::give(std::uint64_t bytes) {
    {
        std::lock_guard lock(mMutex);
        mHeld -= bytes;
    }
    mFreed.notify_all();
}

MemoryBudget::Reservation::Reservation(Reservation&& other) noexcept
    : mBudget(std::exchange(other.mBudget, nullptr)), mBytes(std::exchange(other.mBytes, 0)) {}

MemoryBudget::Reservation& MemoryBudget::Reservation::operator=(Reservation&& other) noexcept {
    if (this != &other) {
        release();
        mBudget = std::exchange(other.mBudget, nullptr);
        mBytes = std::exchange(other.mBytes, 0);
    }
    return *this;
}

MemoryBudget::Reservation::~Reservation() { release(); }

void MemoryBudget::Reservation::release() {
    if (mBudget) mBudget->give(mBytes);
    mBudget = nullptr;
    mBytes = 0;
}

}  // namespace vtex
