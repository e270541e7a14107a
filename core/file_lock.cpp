#include "core/file_lock.hpp"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
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

/// "dir/" and "dir//" name the folder "dir": its lock is "dir.lock" beside it, not "dir/.lock"
/// inside a folder that may not exist yet (export --out dir/ failed with ENOENT on the lock).
std::string WithoutTrailingSlashes(std::string path) {
    while (path.size() > 1 && path.back() == '/') path.pop_back();
    return path;
}

bool EndsWith(const std::string& s, const std::string& tail) {
    return s.size() >= tail.size() && s.compare(s.size() - tail.size(), tail.size(), tail) == 0;
}

/// OUT, OUT.part and OUT.lock share one lock, OUT.lock: a writer given another run's OUT.part
/// as its own output waits for (is refused by) that run instead of replacing its rows; OUT.lock
/// itself is never an output.
std::string LockPathOf(const std::string& path) {
    std::string base = WithoutTrailingSlashes(path);
    if (EndsWith(base, ".lock")) {
        throw std::runtime_error(path +
                                 ": output names a lock file (regbench keeps OUT.lock beside "
                                 "every output it writes); pick another name");
    }
    if (EndsWith(base, ".part")) base.resize(base.size() - 5);
    return base + ".lock";
}

}  // namespace

std::string OutputLockHolder(const std::string& path) {
    std::string lock_path;
    try {
        lock_path = LockPathOf(path);
    } catch (const std::exception&) {
        return "";
    }
    const int fd = ::open(lock_path.c_str(), O_RDONLY | O_NOFOLLOW | O_CLOEXEC | O_NONBLOCK);
    if (fd < 0) return "";
    std::string holder;
    struct stat st {};
    if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode)) {
        if (::flock(fd, LOCK_SH | LOCK_NB) == 0) {
            ::flock(fd, LOCK_UN);
        } else if (errno == EWOULDBLOCK) {
            holder = ReadHolder(fd);
            if (holder == std::to_string(::getpid())) holder.clear();
        }
    }
    ::close(fd);
    return holder;
}

void CreateParentFolders(const std::string& folder) {
    const std::filesystem::path parent =
        std::filesystem::path(WithoutTrailingSlashes(folder)).parent_path();
    if (!parent.empty()) std::filesystem::create_directories(parent);
}

void RequireRegularOrAbsent(const std::string& path, const std::string& what) {
    struct stat st {};
    if (::lstat(path.c_str(), &st) != 0) {
        if (errno == ENOENT) return;
        throw std::runtime_error(path + ": cannot check " + what + ": " + std::strerror(errno));
    }
    if (S_ISLNK(st.st_mode)) {
        throw std::runtime_error(path + ": " + what +
                                 " is a symbolic link; refusing to follow it (remove it)");
    }
    if (!S_ISREG(st.st_mode)) {
        throw std::runtime_error(path + ": " + what +
                                 " exists and is not a regular file; refusing to use it");
    }
    if (st.st_nlink != 1) {
        throw std::runtime_error(path + ": " + what +
                                 " is a hard link shared with another file; refusing to write "
                                 "through it (remove it)");
    }
}

OutputLock::OutputLock(const std::string& path) : lock_path_(LockPathOf(path)), owner_(::getpid()) {
    // Retry when the file we locked was unlinked by a finishing holder between our open and
    // our flock: that inode no longer guards the path.
    for (int attempt = 0; attempt < 100; ++attempt) {
        // Never through a link: a symlink (or a FIFO, a device) pre-placed at the lock path
        // would make the pid write below truncate whatever it points to.
        RequireRegularOrAbsent(lock_path_, "lock file");
        const int fd = ::open(lock_path_.c_str(),
                              O_RDWR | O_CREAT | O_CLOEXEC | O_NOFOLLOW | O_NONBLOCK, 0644);
        if (fd < 0) {
            const int err = errno;
            if (err == ELOOP) RequireRegularOrAbsent(lock_path_, "lock file");  // names the link
            throw std::runtime_error(lock_path_ +
                                     ": cannot create lock file: " + std::strerror(err));
        }
        struct stat opened {};
        if (::fstat(fd, &opened) != 0 || !S_ISREG(opened.st_mode) || opened.st_nlink != 1) {
            ::close(fd);
            throw std::runtime_error(lock_path_ +
                                     ": lock file is not a plain file of its own (a special "
                                     "file or a hard link to another file): refusing to use it");
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
    // A forked child that ran this destructor (it should leave by _exit, but a library may
    // unwind) must not remove the parent's lock: only the process that took it removes it.
    if (::getpid() != owner_) {
        ::close(fd_);
        return;
    }
    // Unlink while still holding the lock, so no newcomer can lock the old inode after us
    // and believe it guards the path (the newcomer's inode check retries instead).
    ::unlink(lock_path_.c_str());
    ::close(fd_);
}

}  // namespace regbench
