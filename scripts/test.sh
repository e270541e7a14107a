#!/usr/bin/env bash
# README command 2: set up (packages, build, data), then run the whole test suite via CTest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root/build"
ctest --output-on-failure -j "$(nproc)" --timeout 900
# Then the sanitizer build, its tests and short fuzzing (REGBENCH_SKIP_EXTRA=1 skips them).
bash "$root/scripts/ci_extra.sh"
