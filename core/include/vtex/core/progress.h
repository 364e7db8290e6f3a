/// @file
/// @brief How a long library operation reports progress without printing anything itself.
///
/// Libraries never print. A long operation takes a Progress&, announces its work with
/// start(), reports units done with advance() (thread-safe, call it coarsely: per tile, per
/// slab, not per voxel) and may be interrupted. The CLI draws a terminal bar from it.
#pragma once

#include <atomic>
#include <cstdint>
#include <string>
#include <string_view>

namespace vtex {

class Progress {
public:
    virtual ~Progress() = default;
    /// A new phase of `total` units of work.
    virtual void start(std::string_view phase, std::uint64_t total) = 0;
    /// `units` more units done; safe to call from several threads.
    virtual void advance(std::uint64_t units) = 0;
    /// The phase is over.
    virtual void finish() = 0;
    /// Polled by long loops; true when the user asked to stop.
    virtual bool wasInterrupted() const { return false; }
};

/// Progress that reports nowhere: the default for library callers and tests.
class NullProgress final : public Progress {
public:
    void start(std::string_view, std::uint64_t) override {}
    void advance(std::uint64_t) override {}
    void finish() override {}
};

/// Progress that only counts, for tests and for callers that want totals afterwards.
class CountingProgress : public Progress {
public:
    void start(std::string_view phase, std::uint64_t total) override;
    void advance(std::uint64_t units) override { mDone.fetch_add(units, std::memory_order_relaxed); }
    void finish() override {}
    std::uint64_t done() const { return mDone.load(std::memory_order_relaxed); }
    std::uint64_t total() const { return mTotal; }
    const std::string& phase() const { return mPhase; }

private:
    std::string mPhase;
    std::uint64_t mTotal = 0;
    std::atomic<std::uint64_t> mDone{0};
};

}  // namespace vtex
