// The memory limit shared by stages that run side by side (core/memory_budget.h): a reservation
// over the whole limit is refused, one that does not fit beside the others waits for them, and
// every reservation is given back when it goes out of scope.
#include <vtex/core/memory_budget.h>

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <thread>

TEST(MemoryBudget, ReservationsWaitForRoomAndGiveItBack) {
    vtex::MemoryBudget budget(100);
    EXPECT_THROW(budget.reserve("x", "too much", 101), vtex::MemoryLimitError);
    std::atomic<bool> second{false};
    std::thread waiter;
    {
        const auto first = budget.reserve("a", "first", 60);
        waiter = std::thread([&] {
            const auto held = budget.reserve("b", "second", 60);  // waits: 60 + 60 > 100
            second = true;
        });
        std::this_thread::sleep_for(std::chrono::milliseconds(50));
        EXPECT_FALSE(second.load()) << "the second reservation did not wait for room";
    }  // the first gives its 60 back
    waiter.join();
    EXPECT_TRUE(second.load());
    const auto all = budget.reserve("c", "all of it", 100);  // both were given back
    vtex::MemoryBudget unlimited(0);
    const auto any = unlimited.reserve("d", "anything", ~std::uint64_t(0));
}

TEST(MemoryBudget, TheRefusalNamesTheFileTheWorkAndBothFigures) {
    try {
        vtex::checkMemoryEstimate("mesh.glb", "sampling at 4096^3", std::uint64_t(5) << 30, std::uint64_t(1) << 30);
        FAIL() << "not refused";
    } catch (const vtex::MemoryLimitError& e) {
        EXPECT_EQ(std::string(e.what()), "mesh.glb: sampling at 4096^3 needs about 5.0 GiB, more than the limit of 1.0 GiB "
                                         "(--max-memory; by default half of this machine's memory)");
        EXPECT_EQ(e.estimate(), std::uint64_t(5) << 30);
    }
    EXPECT_NO_THROW(vtex::checkMemoryEstimate("a", "b", ~std::uint64_t(0), 0));  // 0: no limit
    EXPECT_GT(vtex::defaultMemoryLimit(), std::uint64_t(0));
}

// Found by fuzz_cli.py (third campaign): `vtex run … --max-memory 1` was refused with "more
// than the limit of 0 KiB". Less than a KiB is written in bytes.
TEST(MemoryBudget, FuzzASmallLimitIsWrittenInBytes) {
    EXPECT_EQ(vtex::formatBytes(0), "0 B");
    EXPECT_EQ(vtex::formatBytes(1), "1 B");
    EXPECT_EQ(vtex::formatBytes(1023), "1023 B");
    EXPECT_EQ(vtex::formatBytes(1024), "1 KiB");
    EXPECT_EQ(vtex::formatBytes(3u << 20), "3 MiB");
    EXPECT_EQ(vtex::formatBytes(std::uint64_t(5) << 30), "5.0 GiB");
}
