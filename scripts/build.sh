#!/usr/bin/env bash
# Configures and builds regbench (Release) into build/. Usage: scripts/build.sh [extra cmake args]
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build_dir="${REGBENCH_BUILD_DIR:-$root/build}"
# shellcheck source=scripts/build_env.sh
source "$root/scripts/build_env.sh"
cmake -S "$root" -B "$build_dir" -G Ninja -DCMAKE_BUILD_TYPE=Release "${launcher[@]}" "$@"
cmake --build "$build_dir" -j "$jobs"
