#include "core/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

#include "core/atomic_file.hpp"

namespace regbench {
namespace {

/// The pid a holder wrote into the lock file ("unknown" while it is still being written).
std::string ReadHolder(int fd) {
    char buf[32] = {};
    const ssize_t n = ::pread(fd, buf, sizeof(buf) - 1, 0);
    std::string pid = n > 0 ? std::string(buf, static_cast<std::size_t>(n)) : "";
    while (!pid.empty() && (pid.back() == '\n' || pid.back() == ' ')) pid.pop_back();
    return pid.empty() ? "unknown" : pid;
}

}  // namespace

OutputLock::OutputLock(const std::string& path) : lock_path_(path + ".lock") {
    // Retry when the file we locked was unlinked by a finishing holder between our open and
    // our flock: that inode no longer guards the path.
    for (int attempt = 0; attempt < 100; ++attempt) {
        const int fd = ::open(lock_path_.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
        if (fd < 0) {
            throw std::runtime_error(lock_path_ +
                                     ": cannot create lock file: " + std::strerror(errno));
        }
        if (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
            const int err = errno;
            const std::string holder = ReadHolder(fd);
            ::close(fd);
            if (err == EWOULDBLOCK) {
                throw std::runtime_error(path + ": another regbench process (pid " + holder +
                                         ") is writing this output (lock " + lock_path_ + ")");
            }
            throw std::runtime_error(lock_path_ + ": flock failed: " + std::strerror(err));
        }
        struct stat held {};
        struct stat now {};
        if (::fstat(fd, &held) == 0 && ::stat(lock_path_.c_str(), &now) == 0 &&
            held.st_ino == now.st_ino && held.st_dev == now.st_dev) {
            const std::string pid = std::to_string(::getpid()) + "\n";
            if (::ftruncate(fd, 0) != 0) {
                ::close(fd);
                throw std::runtime_error(lock_path_ + ": cannot write lock file");
            }
            try {
                WriteAllOrThrow(fd, pid, lock_path_);
            } catch (...) {
                ::close(fd);
                throw;
            }
            fd_ = fd;
            return;
        }
        ::close(fd);
    }
    throw std::runtime_error(lock_path_ + ": lock file keeps being replaced");
}

OutputLock::~OutputLock() {
    if (fd_ < 0) return;
    // Unlink while still holding the lock, so no newcomer can lock the old inode after us
    // and believe it guards the path (the newcomer's inode check retries instead).
    ::unlink(lock_path_.c_str());
    ::close(fd_);
}

}  // namespace regbench
