#!/usr/bin/env bash
# Everything a fresh Debian 12 machine needs before regbench runs: packages, build, data.
# REGBENCH_BUILD_TARGETS limits the build (scripts/build.sh); default: every target.
# REGBENCH_MAIN_ONLY=1 (scripts/main_job.sh) installs only the build's packages and configures
# without tests, benchmarks and the Python module; otherwise they are configured on, so a build
# folder first made by the main job gains them.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
start=$(date +%s)
if [ "${REGBENCH_MAIN_ONLY:-0}" = 1 ]; then
  bash "$root/scripts/install_deps.sh" --main
  parts=OFF
else
  bash "$root/scripts/install_deps.sh"
  parts=ON
fi
t1=$(date +%s)
bash "$root/scripts/build.sh" -DREGBENCH_BUILD_TESTS=$parts -DREGBENCH_BUILD_BENCH=$parts \
  -DREGBENCH_PYTHON=$parts
t2=$(date +%s)
bash "$root/scripts/setup_data.sh"
echo "[setup] packages $((t1 - start)) s, build $((t2 - t1)) s" \
  "(targets: ${REGBENCH_BUILD_TARGETS:-all})"
