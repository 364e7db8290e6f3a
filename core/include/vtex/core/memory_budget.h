/// @file
/// @brief The memory a command may plan for, and refusing work that would need more.
///
/// Every stage that can be asked for unbounded work (a sampling resolution, an image size, a
/// volume's file) estimates its peak memory before it starts and refuses, with the estimate in
/// the message and exit status 3, when the estimate exceeds the limit (issue 14, item 4). The
/// commands default to half of the machine's physical memory (defaultMemoryLimit) and take
/// `--max-memory`; the libraries default to no limit (0). In `vtex run`, where stages run side
/// by side, a MemoryBudget shares one limit among them.
#pragma once

#include <vtex/core/error.h>

#include <condition_variable>
#include <cstdint>
#include <filesystem>
#include <mutex>
#include <string>

namespace vtex {

/// Half of this machine's physical memory (bytes); 0 (no limit) where it cannot be read.
std::uint64_t defaultMemoryLimit();

/// "512 MiB", "4.3 GiB": a byte count as a person reads it.
std::string formatBytes(std::uint64_t bytes);

/// Work on `file` would need more memory than allowed. An InputError (exit 3): the input asks
/// for more than this machine is told to give.
class MemoryLimitError : public InputError {
public:
    /// "<file>: <work> needs about <estimate>, more than the limit of <limit> (--max-memory; …)".
    MemoryLimitError(const std::filesystem::path& file, const std::string& work, std::uint64_t estimate,
                     std::uint64_t limit);
    std::uint64_t estimate() const { return mEstimate; }
    std::uint64_t limit() const { return mLimit; }

private:
    std::uint64_t mEstimate, mLimit;
};

/// Throws MemoryLimitError when `limit` is set (not 0) and `estimate` exceeds it.
void checkMemoryEstimate(const std::filesystem::path& file, const std::string& work, std::uint64_t estimate,
                         std::uint64_t limit);

/// One limit shared by work that runs side by side (the stages of a `vtex run` wave): a stage
/// reserves its estimate before it starts and waits while the others' reservations leave too
/// little; a stage whose estimate alone exceeds the limit is refused (MemoryLimitError). A
/// holder never waits for a second reservation, so the waits cannot dead-lock.
class MemoryBudget {
public:
    explicit MemoryBudget(std::uint64_t limit) : mLimit(limit) {}
    MemoryBudget(const MemoryBudget&) = delete;
    MemoryBudget& operator=(const MemoryBudget&) = delete;

    /// Held memory, given back when it goes out of scope.
    class Reservation {
    public:
        Reservation() = default;
        Reservation(Reservation&& other) noexcept;
        Reservation& operator=(Reservation&& other) noexcept;
        ~Reservation();

    private:
        friend class MemoryBudget;
        Reservation(MemoryBudget* budget, std::uint64_t bytes) : mBudget(budget), mBytes(bytes) {}
        void release();
        MemoryBudget* mBudget = nullptr;
        std::uint64_t mBytes = 0;
    };

    /// Waits until `estimate` fits beside what is held, then holds it; throws MemoryLimitError
    /// (naming `file` and `work`) when it exceeds the whole limit. A limit of 0 holds nothing.
    Reservation reserve(const std::filesystem::path& file, const std::string& work, std::uint64_t estimate);

    std::uint64_t limit() const { return mLimit; }

private:
    void give(std::uint64_t bytes);

    const std::uint64_t mLimit;
    std::mutex mMutex;
    std::condition_variable mFreed;
    std::uint64_t mHeld = 0;
};

}  // namespace vtex
