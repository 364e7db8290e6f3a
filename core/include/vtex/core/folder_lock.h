/// @file
/// @brief One writer per output folder: `vtex run` and `vtex demo` hold a lock on the folder
/// they write, so that a second run on it cannot remove the first one's temporaries or mix
/// their outputs (issue 18).
///
/// The lock is flock(2) on `DIR/.vtex.lock`: the kernel drops it when its holder exits, however
/// it exits (a SIGKILL, a killed Slurm job), so the lock of a dead process is simply taken over
/// by the next run; the file itself stays, holding the last holder's host and pid for the
/// message a refused run prints. A run that holds the lock may remove the temporaries it finds
/// (theirs are the writers' who died: AtomicOutputFile names them after host and pid).
#pragma once

#include <filesystem>
#include <string>

namespace vtex {

class FolderLock {
public:
    enum class Mode { Refuse, Wait };
    /// Exclusive: one holder (a whole run). Shared: any number of shared holders at once, and no
    /// exclusive one (the stages of one cluster submission, `vtex run --stage`, each of which
    /// also takes its stage's own lock exclusively).
    enum class Access { Exclusive, Shared };
    /// Locks `folder` (which must exist) through its file `name`. Refuse: throws IoError naming
    /// the folder and the holder ("in use by host:1234") when another process holds it in a way
    /// that excludes this one; Wait: blocks until it is free.
    explicit FolderLock(const std::filesystem::path& folder, Mode mode = Mode::Refuse,
                        Access access = Access::Exclusive, const std::string& name = ".vtex.lock");
    ~FolderLock();
    FolderLock(const FolderLock&) = delete;
    FolderLock& operator=(const FolderLock&) = delete;

    /// "host:pid", how this process names itself in lock files and temporaries' names.
    static std::string holderName();

private:
    int mFd = -1;
};

}  // namespace vtex
