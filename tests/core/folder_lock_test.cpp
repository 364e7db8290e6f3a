// One writer per output folder (core/folder_lock.h): a second holder is refused naming the
// first, or waits for it; the lock of a process that died (SIGKILL included) is taken over.
#include <vtex/core/error.h>
#include <vtex/core/folder_lock.h>

#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <thread>

#include <csignal>
#include <sys/wait.h>
#include <unistd.h>

namespace fs = std::filesystem;

namespace {

fs::path freshFolder(const std::string& name) {
    const fs::path dir = fs::path(VTEX_TEST_TMP) / "folder_lock" / name;
    fs::remove_all(dir);
    fs::create_directories(dir);
    return dir;
}

// A child process that takes the lock, says so through a pipe, and then sleeps `holdMs`.
pid_t holdInChild(const fs::path& dir, int holdMs) {
    int ready[2];
    if (::pipe(ready) != 0) return -1;
    const pid_t child = ::fork();
    if (child == 0) {
        ::close(ready[0]);
        const vtex::FolderLock lock(dir);
        (void)!::write(ready[1], "x", 1);
        std::this_thread::sleep_for(std::chrono::milliseconds(holdMs));
        ::_exit(0);
    }
    ::close(ready[1]);
    char c = 0;
    (void)!::read(ready[0], &c, 1);  // returns once the child holds the lock
    ::close(ready[0]);
    return child;
}

}  // namespace

TEST(FolderLock, ASecondHolderIsRefusedNamingTheFirst) {
    const fs::path dir = freshFolder("refuse");
    const pid_t child = holdInChild(dir, 10000);
    ASSERT_GT(child, 0);
    try {
        const vtex::FolderLock second(dir);
        FAIL() << "a second lock was granted";
    } catch (const vtex::IoError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find(dir.string()), std::string::npos) << what;
        EXPECT_NE(what.find("in use by"), std::string::npos) << what;
        EXPECT_NE(what.find(":" + std::to_string(child)), std::string::npos) << what;
    }
    // Killed, as a SIGKILL or a cancelled job kills: its lock is taken over at once.
    ::kill(child, SIGKILL);
    ::waitpid(child, nullptr, 0);
    EXPECT_NO_THROW(vtex::FolderLock taken(dir));
}

TEST(FolderLock, WaitBlocksUntilTheHolderLeaves) {
    const fs::path dir = freshFolder("wait");
    const auto start = std::chrono::steady_clock::now();
    const pid_t child = holdInChild(dir, 300);
    ASSERT_GT(child, 0);
    {
        const vtex::FolderLock waited(dir, vtex::FolderLock::Mode::Wait);
        EXPECT_GE(std::chrono::steady_clock::now() - start, std::chrono::milliseconds(250));
    }
    ::waitpid(child, nullptr, 0);
    // Released when it goes out of scope: the next one gets it without waiting.
    EXPECT_NO_THROW(vtex::FolderLock again(dir));
}
