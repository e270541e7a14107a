#!/usr/bin/env bash
# Configures and builds regbench (Release) into build/. Usage: scripts/build.sh [extra cmake args]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
jobs="${REGBENCH_BUILD_JOBS:-$(nproc)}"
build_dir="${REGBENCH_BUILD_DIR:-$root/build}"
launcher=()
# ccache (when installed) makes rebuilds and several worktrees cheap; CCACHE_BASEDIR lets
# worktrees at different paths share hits.
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
fi
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
cmake --build "$build_dir" -j "$jobs"
