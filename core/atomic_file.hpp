#pragma once
// Atomic, checked output files: every writer in regbench (pair files, results, reports, exports)
// goes through here, so a full disk, a quota or a file-size limit can never leave a half-written
// file at the final path, and an output can never replace one of its own inputs.
#include <string>
#include <string_view>
#include <vector>

namespace regbench {

/// Refuses an output path that cannot be replaced atomically or would destroy an input: `out`
/// must not be a directory, must be a regular file if it exists (not /dev/full, a FIFO, ...),
/// must not be the same file as any of `inputs` (checked by inode, so links and ./a vs a are
/// caught), and its directory must exist. Throws std::runtime_error naming `out`.
void CheckOutputPath(const std::string& out, const std::vector<std::string>& inputs = {});

/// A file written under a temporary name in the final directory and renamed into place by
/// Commit(). Every write, flush, fsync and close is checked; a failure throws naming the final
/// path and removes the temporary, as does destroying an uncommitted AtomicFile.
///
/// Libraries that write by file name (HDF5) use temp_path() and then Commit(), which fsyncs the
/// library's bytes before the rename.
class AtomicFile {
public:
    /// Checks `path` with CheckOutputPath(path, inputs) and creates the temporary file.
    explicit AtomicFile(std::string path, const std::vector<std::string>& inputs = {});
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    /// Appends bytes; throws on a short or failed write (ENOSPC, EFBIG, EIO).
    void Write(std::string_view data);
    /// fsync, close, rename over the final path, fsync the directory. Throws on any failure.
    void Commit();
    /// Removes the temporary file (idempotent, never throws).
    void Abort() noexcept;

    const std::string& path() const { return path_; }
    const std::string& temp_path() const { return temp_; }

private:
    std::string path_;
    std::string temp_;
    int fd_ = -1;
    bool done_ = false;
    int owner_ = 0;  ///< pid that created the temporary; only it removes it
};

/// Writes `content` to `path` atomically (AtomicFile in one call).
void WriteFileAtomic(const std::string& path, std::string_view content,
                     const std::vector<std::string>& inputs = {});

/// Writes all of `data` to `fd`, retrying short writes and EINTR. Throws naming `what`.
void WriteAllOrThrow(int fd, std::string_view data, const std::string& what);

}  // namespace regbench
