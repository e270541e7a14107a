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

/// Throws std::runtime_error "<what> <path>: ..." unless `path` (links followed) is an existing
/// regular file: a missing file, a folder, a FIFO, a socket or a device is refused by name.
/// `what` names the kind of input ("training bundle"), when the caller's message would.
inline void RequireRegularFile(const std::string& path, const std::string& what = "") {
    const std::string name = what.empty() ? path : what + " " + path;
    struct stat st {};
    if (::stat(path.c_str(), &st) != 0) {
        throw std::runtime_error(name + ": " +
                                 (errno == ENOENT
                                      ? std::string("no such file")
                                      : "cannot open: " + std::string(std::strerror(errno))));
    }
    if (S_ISDIR(st.st_mode)) throw std::runtime_error(name + ": is a directory, not a file");
    if (!S_ISREG(st.st_mode)) {
        throw std::runtime_error(name +
                                 ": not a regular file (a FIFO, socket or device); regbench reads "
                                 "inputs from regular files only");
    }
}

}  // namespace regbench
