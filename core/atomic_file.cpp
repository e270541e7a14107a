#include "core/atomic_file.hpp"

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <stdexcept>

namespace regbench {
namespace {

namespace fs = std::filesystem;

[[noreturn]] void Fail(const std::string& path, const std::string& what) {
    throw std::runtime_error(path + ": " + what);
}

std::string ErrnoText() { return std::strerror(errno); }

/// The directory a path lives in ("." for a bare name).
std::string DirOf(const std::string& path) {
    const fs::path parent = fs::path(path).parent_path();
    return parent.empty() ? std::string(".") : parent.string();
}

/// fsync on the directory makes the rename itself durable (POSIX leaves it to the caller).
void SyncDirectory(const std::string& dir) {
    const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
    if (fd < 0) return;  // some filesystems refuse; the rename has still happened
    ::fsync(fd);
    ::close(fd);
}

}  // namespace

void CheckOutputPath(const std::string& out, const std::vector<std::string>& inputs) {
    if (out.empty()) throw std::invalid_argument("output path is empty");
    struct stat st {};
    if (::stat(out.c_str(), &st) == 0) {
        if (S_ISDIR(st.st_mode)) Fail(out, "output is a directory");
        if (!S_ISREG(st.st_mode)) {
            Fail(out, "output exists and is not a regular file (refusing to replace it)");
        }
        for (const auto& in : inputs) {
            struct stat ist {};
            if (!in.empty() && ::stat(in.c_str(), &ist) == 0 && ist.st_dev == st.st_dev &&
                ist.st_ino == st.st_ino) {
                Fail(out, "output is the same file as the input " + in);
            }
        }
    }
    const std::string dir = DirOf(out);
    struct stat dst {};
    if (::stat(dir.c_str(), &dst) != 0 || !S_ISDIR(dst.st_mode)) {
        Fail(out, "directory " + dir + " does not exist");
    }
}

void WriteAllOrThrow(int fd, std::string_view data, const std::string& what) {
    std::size_t off = 0;
    while (off < data.size()) {
        const ssize_t n = ::write(fd, data.data() + off, data.size() - off);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) Fail(what, "write failed: " + (n < 0 ? ErrnoText() : "no progress"));
        off += static_cast<std::size_t>(n);
    }
}

AtomicFile::AtomicFile(std::string path, const std::vector<std::string>& inputs)
    : path_(std::move(path)), owner_(::getpid()) {
    CheckOutputPath(path_, inputs);
    // A unique name in the final directory: the rename stays on one filesystem (atomic), and
    // two writers never share a temporary.
    const fs::path p(path_);
    std::string templ =
        (fs::path(DirOf(path_)) / ("." + p.filename().string() + ".tmp.XXXXXX")).string();
    fd_ = ::mkstemp(templ.data());
    if (fd_ < 0) Fail(path_, "cannot create a temporary file: " + ErrnoText());
    temp_ = templ;
    ::fchmod(fd_, 0644);  // mkstemp's 0600 would make results private to the writer
}

AtomicFile::~AtomicFile() { Abort(); }

void AtomicFile::Write(std::string_view data) {
    if (done_ || fd_ < 0) Fail(path_, "write after commit");
    try {
        WriteAllOrThrow(fd_, data, path_);
    } catch (...) {
        Abort();
        throw;
    }
}

void AtomicFile::Commit() {
    if (done_) Fail(path_, "committed twice");
    auto fail = [&](const std::string& what) {
        const std::string msg = what + ": " + ErrnoText();
        Abort();
        Fail(path_, msg);
    };
    // Bytes a library wrote by name (HDF5) are synced through a fresh descriptor.
    if (fd_ < 0) {
        fd_ = ::open(temp_.c_str(), O_RDONLY | O_CLOEXEC);
        if (fd_ < 0) fail("cannot reopen temporary file");
    }
    if (::fsync(fd_) != 0) fail("fsync failed");
    const int fd = fd_;
    fd_ = -1;
    if (::close(fd) != 0) fail("close failed");
    if (::rename(temp_.c_str(), path_.c_str()) != 0) fail("cannot rename temporary file");
    done_ = true;
    SyncDirectory(DirOf(path_));
}

void AtomicFile::Abort() noexcept {
    if (fd_ >= 0) {
        ::close(fd_);
        fd_ = -1;
    }
    // A forked child never removes its parent's temporary.
    if (!done_ && !temp_.empty() && ::getpid() == owner_) ::unlink(temp_.c_str());
    done_ = true;
}

void WriteFileAtomic(const std::string& path, std::string_view content,
                     const std::vector<std::string>& inputs) {
    AtomicFile file(path, inputs);
    file.Write(content);
    file.Commit();
}

}  // namespace regbench
