#!/usr/bin/env bash
# Everything a fresh Debian 12 machine needs before regbench runs: packages, build, data.
# REGBENCH_BUILD_TARGETS limits the build (scripts/build.sh); default: every target.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
start=$(date +%s)
bash "$root/scripts/install_deps.sh"
t1=$(date +%s)
bash "$root/scripts/build.sh"
t2=$(date +%s)
bash "$root/scripts/setup_data.sh"
echo "[setup] packages $((t1 - start)) s, build $((t2 - t1)) s" \
  "(targets: ${REGBENCH_BUILD_TARGETS:-all})"
