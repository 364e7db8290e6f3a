#include <vtex/core/progress.h>

namespace vtex {

void CountingProgress::start(std::string_view phase, std::uint64_t total) {
    mPhase = phase;
    mTotal = total;
    mDone.store(0, std::memory_order_relaxed);
}

}  // namespace vtex
