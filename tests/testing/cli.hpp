#pragma once
// Runs the built `regbench` binary (REGBENCH_CLI, set by tests/CMakeLists.txt for the app
// tests) through the shell and captures what it prints.
#include <stdexcept>
#include <string>

#include "tests/testing/shell.hpp"

namespace regbench::testing {

/// `regbench ARGS 2>&1`; ARGS is passed to the shell as written.
inline CliResult RunCli(const std::string& args) {
    return RunShell(std::string(REGBENCH_CLI) + " " + args + " 2>&1");
}

/// RunCli under `timeout SECONDS`: a hang ends with exit 124 instead of hanging the test.
inline CliResult RunCliWithin(int seconds, const std::string& args) {
    return RunShell("timeout " + std::to_string(seconds) + " " + std::string(REGBENCH_CLI) + " " +
                    args + " 2>&1");
}

/// `regbench ARGS`, which must succeed: throws (failing the calling test) with what it printed.
inline void RunCliOk(const std::string& args) {
    const CliResult r = RunCli(args);
    if (r.exit_code != 0) throw std::runtime_error("regbench " + args + ": " + r.output);
}

/// A small pair file (`pairs` procedural partial pairs of 64 points) written to `path`.
inline std::string SmallPairFile(const std::string& path, int pairs) {
    RunCliOk("generate --protocol partial --dataset procedural --pairs " + std::to_string(pairs) +
             " --points 64 --out " + path);
    return path;
}

}  // namespace regbench::testing
