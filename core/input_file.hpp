#pragma once
// Inputs are read from regular files only: opening a FIFO blocks until a writer appears (for
// ever), and a link to /dev/zero or /dev/urandom never ends. Every reader of a named file calls
// RequireRegularFile before opening it (issue 44).
#include <sys/stat.h>

#include <cerrno>
#include <cstring>
#include <stdexcept>
#include <string>

namespace regbench {

/// Throws std::runtime_error "<path>: ..." unless `path` (links followed) is an existing
/// regular file: a missing file, a folder, a FIFO, a socket or a device is refused by name.
inline void RequireRegularFile(const std::string& path) {
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        throw std::runtime_error(path + ": " +
                                 (errno == ENOENT
                                      ? std::string("no such file")
                                      : "cannot open: " + std::string(std::strerror(errno))));
    }
    if (S_ISDIR(st.st_mode)) throw std::runtime_error(path + ": is a directory, not a file");
    if (!S_ISREG(st.st_mode)) {
        throw std::runtime_error(path +
                                 ": not a regular file (a FIFO, socket or device); regbench reads "
                                 "inputs from regular files only");
    }
}

}  // namespace regbench
