#!/usr/bin/env bash
# README command 2: set up (packages, build, data), then run the whole test suite via CTest.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$root/scripts/setup.sh"
cd "$root/build"
ctest --output-on-failure -j "$(nproc)" --timeout 900
# Sanitizer build + fuzzing: opt-in with REGBENCH_CI_EXTRA=1 until one full run of it has been
# timed on the CI machine (it has not completed on the shared development VM yet).
if [ "${REGBENCH_CI_EXTRA:-0}" = 1 ]; then
  bash "$root/scripts/ci_extra.sh"
fi
