#include <vtex/core/atomic_file.h>

#include <vtex/core/error.h>
#include <vtex/core/folder_lock.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <random>
#include <string>

#include <fcntl.h>
#include <unistd.h>

namespace vtex {
namespace {

std::string systemError() { return std::strerror(errno); }

// fsync through a fresh descriptor: std::ofstream does not expose its own.
void syncPath(const std::filesystem::path& path, bool isDirectory) {
    const int fd = ::open(path.c_str(), (isDirectory ? O_DIRECTORY : 0) | O_RDONLY | O_CLOEXEC);
    if (fd < 0) throw IoError(path, "cannot open for syncing: " + systemError());
    const int status = ::fsync(fd);
    const std::string reason = status != 0 ? systemError() : std::string();
    ::close(fd);
    // Some file systems (tmpfs, some FUSE mounts) refuse fsync on directories; the rename is
    // atomic all the same.
    if (status != 0 && !isDirectory) throw IoError(path, "cannot flush to disk: " + reason);
}

const char* kindOf(std::filesystem::file_type type) {
    switch (type) {
    case std::filesystem::file_type::regular: return "a regular file";
    case std::filesystem::file_type::directory: return "a directory";
    case std::filesystem::file_type::fifo: return "a FIFO";
    case std::filesystem::file_type::character: return "a character device";
    case std::filesystem::file_type::block: return "a block device";
    case std::filesystem::file_type::socket: return "a socket";
    default: return "not a regular file";
    }
}

// The output is one of the command's inputs, links followed (st_dev and st_ino, through
// filesystem::equivalent): writing it would replace what the command reads.
void refuseOwnInput(const std::filesystem::path& target, const std::vector<std::filesystem::path>& inputs) {
    std::error_code error;
    for (const auto& input : inputs)
        if (!input.empty() && std::filesystem::equivalent(target, input, error))
            throw InputError(target, "output is the command's own input " + input.string());
}

}  // namespace

void checkOutputPath(const std::filesystem::path& target, const std::vector<std::filesystem::path>& inputs) {
    std::error_code error;
    const auto status = std::filesystem::status(target, error);
    if (error || !std::filesystem::exists(status)) {
        // A new path, which its folder must hold: `vtex sample -r 4096 -o missing/x.vtl` sampled
        // for minutes before it found out (found by fuzz_cli.py). The same words as below.
        std::filesystem::path directory = target.parent_path();
        if (directory.empty()) directory = ".";
        if (!std::filesystem::is_directory(directory, error)) throw IoError(target, "output directory does not exist");
        return;
    }
    if (status.type() != std::filesystem::file_type::regular)
        throw InputError(target, std::string("output is ") + kindOf(status.type()) +
                                     ": vtex writes only regular files or new paths");
    refuseOwnInput(target, inputs);
}

void checkOutputFolder(const std::filesystem::path& folder, const std::vector<std::filesystem::path>& inputs) {
    std::error_code error;
    const auto status = std::filesystem::status(folder, error);
    if (error || !std::filesystem::exists(status)) return;  // a new folder
    refuseOwnInput(folder, inputs);  // before the kind: "its own input" says more than "a regular file"
    if (status.type() != std::filesystem::file_type::directory)
        throw InputError(folder, std::string("output folder is ") + kindOf(status.type()) +
                                     ": vtex writes into a directory or makes a new one");
}

AtomicOutputFile::AtomicOutputFile(std::filesystem::path target) : mTarget(std::move(target)) {
    if (mTarget.empty()) throw IoError(mTarget, "empty output path");
    // With error codes: a name too long or a link loop made the throwing overloads escape as
    // std::filesystem's own "filesystem error: status: …" (found by fuzz_cli.py); such a path
    // fails below, when its temporary cannot be created, with vtex's message.
    std::error_code error;
    if (std::filesystem::is_directory(mTarget, error))
        throw IoError(mTarget, "is a directory, expected a file name");
    checkOutputPath(mTarget);
    std::filesystem::path directory = mTarget.parent_path();
    if (directory.empty()) directory = ".";
    if (!std::filesystem::is_directory(directory, error))
        throw IoError(mTarget, "output directory does not exist");

    // Hidden, and named after the target, so a stray temporary is easy to attribute. Not
    // mkstemp: its files are mode 0600, and an output should get the user's umask like any
    // other file, so the temporary is created 0666 & ~umask with O_EXCL and a unique suffix.
    // And after its writer (host and pid, FolderLock::holderName): on a shared folder the
    // temporaries of a live writer elsewhere are told from a dead one's.
    static const std::string writer = [] {
        std::string name = FolderLock::holderName();
        for (char& c : name)
            if (c == ':' || c == '/') c = '.';
        return name;
    }();
    static std::atomic<unsigned> counter{0};
    std::random_device entropy;
    for (int attempt = 0; attempt < 100; ++attempt) {
        char suffix[32];
        std::snprintf(suffix, sizeof suffix, ".%u.%08x", counter.fetch_add(1), unsigned(entropy()));
        std::string name = ".";
        name += mTarget.filename().string();
        name += ".tmp.";
        name += writer;
        name += suffix;
        const std::filesystem::path candidate = directory / name;
        const int fd = ::open(candidate.c_str(), O_CREAT | O_EXCL | O_WRONLY | O_CLOEXEC, 0666);
        if (fd >= 0) {
            ::close(fd);
            mTemporary = candidate;
            return;
        }
        if (errno != EEXIST) throw IoError(mTarget, "cannot create a temporary file beside it: " + systemError());
    }
    throw IoError(mTarget, "cannot create a temporary file beside it: every name tried exists");
}

AtomicOutputFile::~AtomicOutputFile() {
    if (mCommitted) return;
    if (mStream.is_open()) mStream.close();
    std::error_code ignored;
    std::filesystem::remove(mTemporary, ignored);
}

std::ostream& AtomicOutputFile::stream() {
    if (!mStream.is_open()) {
        mStream.open(mTemporary, std::ios::binary | std::ios::trunc);
        if (!mStream) throw IoError(mTemporary, "cannot open temporary file for writing");
    }
    return mStream;
}

void AtomicOutputFile::finish() {
    if (mFinished) return;
    if (mStream.is_open()) {
        mStream.flush();
        const bool failed = !mStream;
        mStream.close();
        if (failed || mStream.fail()) throw IoError(mTarget, "write failed (disk full?)");
    }
    syncPath(mTemporary, false);
    mFinished = true;
}

void commitAll(std::initializer_list<AtomicOutputFile*> files) {
    for (AtomicOutputFile* file : files)
        if (file) file->finish();
    for (AtomicOutputFile* file : files)
        if (file) file->commit();
}

void AtomicOutputFile::commit() {
    if (mCommitted) return;
    finish();
    if (::rename(mTemporary.c_str(), mTarget.c_str()) != 0)
        throw IoError(mTarget, "cannot move the finished file into place: " + systemError());
    mCommitted = true;
    std::filesystem::path directory = mTarget.parent_path();
    syncPath(directory.empty() ? std::filesystem::path(".") : directory, true);
}

void writeFileAtomically(const std::filesystem::path& target, std::string_view bytes) {
    AtomicOutputFile file(target);
    file.stream().write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
    file.commit();
}

}  // namespace vtex
