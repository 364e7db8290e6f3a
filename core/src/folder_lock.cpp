#include <vtex/core/folder_lock.h>

#include <vtex/core/error.h>

#include <cerrno>
#include <cstring>
#include <string>

#include <fcntl.h>
#include <sys/file.h>
#include <unistd.h>

namespace vtex {
namespace {

std::string readHolder(int fd) {
    char text[256] = {};
    const ssize_t n = ::pread(fd, text, sizeof text - 1, 0);
    std::string holder = n > 0 ? std::string(text, std::size_t(n)) : std::string("another process");
    while (!holder.empty() && (holder.back() == '\n' || holder.back() == '\0')) holder.pop_back();
    return holder;
}

}  // namespace

std::string FolderLock::holderName() {
    char host[256] = {};
    if (::gethostname(host, sizeof host - 1) != 0) std::strcpy(host, "unknown-host");
    return std::string(host) + ":" + std::to_string(::getpid());
}

FolderLock::FolderLock(const std::filesystem::path& folder, Mode mode, Access access, const std::string& name) {
    const std::filesystem::path file = folder / name;
    mFd = ::open(file.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0666);
    if (mFd < 0) throw IoError(file, std::string("cannot open the folder's lock: ") + std::strerror(errno));
    const int operation = (access == Access::Shared ? LOCK_SH : LOCK_EX) | (mode == Mode::Wait ? 0 : LOCK_NB);
    int status;
    while ((status = ::flock(mFd, operation)) != 0 && errno == EINTR) {
    }
    if (status != 0) {
        const int error = errno;
        const std::string holder = readHolder(mFd);
        ::close(mFd);
        mFd = -1;
        if (error == EWOULDBLOCK)
            throw IoError(folder, "in use by " + holder + " (another vtex run or demo writes into it); wait for it "
                                  "to finish, or pass --wait");
        throw IoError(file, std::string("cannot lock the folder: ") + std::strerror(error));
    }
    // Ours now: say who holds it, for the message of a run refused meanwhile (best effort: the
    // lock holds without its note, and a refused run then names "another process").
    const std::string me = holderName() + "\n";
    if (::ftruncate(mFd, 0) == 0) (void)!::pwrite(mFd, me.data(), me.size(), 0);
}

FolderLock::~FolderLock() {
    if (mFd >= 0) ::close(mFd);  // releases the flock
}

}  // namespace vtex
