#!/usr/bin/env bash
# Configures and builds regbench (Release) into build/. Usage: scripts/build.sh [extra cmake args]
# REGBENCH_BUILD_TARGETS (space-separated; default: everything, tests and benchmarks included)
# limits the build: scripts/main_job.sh builds only the `regbench` binary.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${REGBENCH_BUILD_DIR:-$root/build}"
# shellcheck source=scripts/build_env.sh
source "$root/scripts/build_env.sh"
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
targets=()
for t in ${REGBENCH_BUILD_TARGETS:-}; do targets+=(--target "$t"); done
cmake --build "$build_dir" -j "$jobs" "${targets[@]}"
