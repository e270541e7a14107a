#pragma once
// One writer per output: an exclusive flock on "<path>.lock" held for the writer's lifetime.
#include <string>

namespace regbench {

/// Takes an exclusive, non-blocking flock on `path` + ".lock" and writes this process's pid
/// into it. Throws std::runtime_error naming the output and the holder's pid when another
/// process (or another OutputLock in this one) holds it. The kernel drops the lock when the
/// process dies, so a killed run never leaves a stale lock behind; the destructor also removes
/// the lock file.
class OutputLock {
public:
    explicit OutputLock(const std::string& path);
    ~OutputLock();
    OutputLock(const OutputLock&) = delete;
    OutputLock& operator=(const OutputLock&) = delete;

    const std::string& lock_path() const { return lock_path_; }

private:
    std::string lock_path_;
    int fd_ = -1;
};

}  // namespace regbench
