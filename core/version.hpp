#pragma once
// The regbench version and git commit this build came from, for `--version` and the
// provenance of pair files, checkpoints and benchmarks. Both live in one file generated at
// configure time (core/version.cpp.in), so a new commit recompiles that file only.

namespace regbench {

/// The CMake project version, e.g. "0.1.0".
const char* RegbenchVersion();

/// `git rev-parse --short=12 HEAD` at configure time; "unknown" outside a git checkout.
const char* RegbenchGitSha();

/// The source tree this binary was built from (absolute path at configure time).
const char* RegbenchSourceDir();

}  // namespace regbench
