#pragma once
// Runs a shell command and captures what it prints (the CLI tests, the Python-written fixtures).
#include <sys/wait.h>

#include <cstdio>
#include <string>

namespace regbench::testing {

struct CliResult {
    int exit_code = -1;  ///< -1: killed by a signal
    std::string output;  ///< stdout and stderr
};

/// Runs the shell command `cmd` and captures what it prints.
inline CliResult RunShell(const std::string& cmd) {
    CliResult r;
    FILE* p = popen(cmd.c_str(), "r");
    if (p == nullptr) return r;
    char buf[4096];
    std::size_t n = 0;
    while ((n = fread(buf, 1, sizeof(buf), p)) > 0) r.output.append(buf, n);
    const int status = pclose(p);
    r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return r;
}

}  // namespace regbench::testing
