#!/usr/bin/env bash
# Installs the Debian 12 packages regbench needs. Idempotent: installs only what is missing.
# The python3-* packages and pybind11-dev build and test the `regbench` Python module
# (python/, docs/python.md: pybind11, NumPy; pytest, scipy, h5py and pandas in its tests; Open3D
# in scripts/example_open3d_icp.py). --reference also installs what scripts/probreg_reference.py
# needs to run probreg (more Python modules for /usr/bin/python3 and pybind11 to build probreg's
# extensions; see docs/probreg-equivalence.md). The C++ build and tests do not need them. chromium renders the
# HTML report headless in its test (docs/reports.md). clang + libclang-rt-14-dev build the
# sanitizer + libFuzzer stage of the test command (scripts/ci_extra.sh). ccache makes rebuilds
# (that stage, worktrees, re-runs) cheap; it is in the --main list too, because
# scripts/build_env.sh makes it the compiler launcher when installed: had only the full list
# installed it, the test command's configure would change every compile command and recompile
# all the main job built (tests/cli/build_config_same.sh).
# --main installs only what the `regbench` binary and its data need (README command 1,
# scripts/main_job.sh): about 860 MB fewer to fetch and unpack than the full list. libdlib-dev:
# dlib's linear assignment (max_cost_assignment) for RGM's test time (networks/families/rgm/assignment.cpp).
set -euo pipefail

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libnanoflann-dev libhdf5-dev nlohmann-json3-dev libcli11-dev
  libfmt-dev libspdlog-dev
  libopen3d-dev libpcl-dev libcgal-dev libcgal-demo
  libtorch-dev libopenblas0-openmp libopenblas-dev libsvm-dev zlib1g-dev libdlib-dev
  ccache
)
if [ "${1:-}" != "--main" ]; then
  PACKAGES+=(
    libgtest-dev libgmock-dev libbenchmark-dev chromium
    python3-dev pybind11-dev python3-numpy python3-scipy python3-h5py python3-pandas
    python3-pytest python3-open3d python3-torch
    clang libclang-rt-14-dev
    slurmctld slurmd slurm-client munge
  )
fi
if [ "${1:-}" = "--reference" ]; then
  PACKAGES+=(
    python3-sklearn python3-transforms3d python3-six python3-matplotlib python3-pybind11
  )
fi

missing=()
for p in "${PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "[install_deps] all ${#PACKAGES[@]} packages present"
  exit 0
fi

SUDO=""
if [ "$(id -u)" -ne 0 ]; then SUDO="sudo"; fi
echo "[install_deps] installing: ${missing[*]}"
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq
$SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
