// ImageOptions::threads bounds the whole render, load included: the texels' chord measures (the
// level fit, the hybrid's switch, the lit fractions) run in parallel loops of their own, which
// ran in the caller's arena on every core whatever the option said (`vtex render --threads 1`
// took both of this machine's). A TBB observer of the caller's arena sees every worker that
// joins it: none may while a render runs, which then runs in an arena of its own of `threads`
// (stats.threads).
#include <gtest/gtest.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <tbb/task_scheduler_observer.h>
#include <vtex/render/reference.h>

#include <atomic>
#include <cmath>
#include <thread>

#include "bush_field.h"

namespace {

using namespace vtex::render;
using namespace vtex::render::test;

// Counts the workers that join `arena` while it lives.
class WorkerCount : public tbb::task_scheduler_observer {
public:
    explicit WorkerCount(tbb::task_arena& arena) : tbb::task_scheduler_observer(arena) { observe(true); }
    void on_scheduler_entry(bool isWorker) override {
        if (isWorker) ++mWorkers;
    }
    int workers() const { return mWorkers.load(); }

private:
    std::atomic<int> mWorkers{0};
};

// The arena a caller renders from, with room for a worker, and its observer. Never destroyed:
// a worker that joined the arena holds a reference to the observer's TBB proxy, which TBB frees
// only when that worker next walks the arena's observer list, possibly after the process's leak
// check (LeakSanitizer reported the proxy in the sanitizer half of .ci/run, in one run of
// several, whether the observed arena was the thread's implicit one or the test's own). Kept
// reachable from a static, nothing leaks; each test has its own, so no late worker of one test
// counts in another run in the same process.
struct ObservedArena {
    tbb::task_arena arena{2};
    WorkerCount count{arena};
};

// A parallel loop as long as a render's load: workers join the arena it runs in.
void busyLoop() {
    std::atomic<int> finite{0};
    tbb::parallel_for(0, 1 << 12, [&](int i) {
        double x = i;
        for (int k = 0; k < 20000; ++k) x = x * 0.999 + 1;
        if (std::isfinite(x)) ++finite;
    });
    EXPECT_EQ(finite.load(), 1 << 12);
}

TEST(Threads, ARenderAskedForOneThreadRunsItsLoadAndTilesOnOne) {
    if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one core: no worker could join anyway";
    const Scene scene = bushField(Eigen::Vector3d(0.5, -3, 3), 24);
    RenderOptions options;
    options.threads = 1;
    static ObservedArena* const caller = new ObservedArena;
    const int before = caller->count.workers();  // the arena outlives a run (--gtest_repeat)
    caller->arena.execute([&] {
        const RenderResult result = renderQuiet(scene, options);
        EXPECT_EQ(result.stats.threads, 1);
        EXPECT_GT(result.stats.voxelsVisited, 0u);
    });
    EXPECT_EQ(caller->count.workers(), before);
    // The observer does see workers that join the caller's arena (the test would catch nothing
    // otherwise).
    caller->arena.execute(busyLoop);
    EXPECT_GT(caller->count.workers(), before);
}

TEST(Threads, AReferenceAskedForOneThreadRunsOnOne) {
    if (std::thread::hardware_concurrency() < 2) GTEST_SKIP() << "one core: no worker could join anyway";
    const Scene scene = bushField(Eigen::Vector3d(0.5, -3, 3), 24);
    ReferenceOptions options;
    options.threads = 1;
    static ObservedArena* const caller = new ObservedArena;
    const int before = caller->count.workers();
    caller->arena.execute([&] {
        vtex::NullProgress progress;
        EXPECT_EQ(renderReference(scene, options, progress).stats.threads, 1);
    });
    EXPECT_EQ(caller->count.workers(), before);
}

}  // namespace
