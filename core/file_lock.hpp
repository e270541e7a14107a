#pragma once
// One writer per output: an exclusive flock on "<path>.lock" held for the writer's lifetime.
#include <string>

namespace regbench {

/// Takes an exclusive, non-blocking flock on `path` + ".lock" and writes this process's pid
/// into it. Throws std::runtime_error naming the output and the holder's pid when another
/// process (or another OutputLock in this one) holds it. The kernel drops the lock when the
/// process dies, so a killed run never leaves a stale lock behind; the destructor also removes
/// the lock file, but only in the process that took the lock (never in a forked child). The
/// lock path is opened without following links (O_NOFOLLOW) and only as a plain file.
/// Throws std::runtime_error naming `path` (described as `what`) unless nothing exists there
/// or it is a regular file with a single link: a symbolic link, a hard link shared with
/// another file, a FIFO or a device at a path regbench writes (lock, .part, temporary files)
/// is refused, never followed.
void RequireRegularOrAbsent(const std::string& path, const std::string& what);

/// For the commands whose output is a folder they create (`reproduce`, `export`, `train`,
/// `import-checkpoint`): creates the folder's missing parents, as `mkdir -p` would, so that the
/// lock beside the folder can be taken (`reproduce --out out/reproduce` in a fresh clone, where
/// `out/` does not exist yet, failed with "cannot create lock file"). The folder itself is left
/// to the command. Commands that write one file keep refusing a missing directory.
void CreateParentFolders(const std::string& folder);

/// The pid (as its lock file records it) of another process that holds the output lock of
/// `path` right now; "" when none does, when this process holds it, or when `path` names a
/// lock file. Takes no lock and creates nothing.
std::string OutputLockHolder(const std::string& path);

/// The lock of "OUT" and of "OUT.part" is "OUT.lock" (a run's partial file is covered by its
/// lock); a path ending in ".lock" is refused.
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
    int owner_ = 0;  ///< pid that took the lock; only it removes the file
};

}  // namespace regbench
