#!/usr/bin/env bash
# Trains a training bundle on a GPU machine that has PyTorch (with its LibTorch), CMake, Ninja
# and a C++ compiler, but none of Debian's Open3D, PCL, CGAL, HDF5 or CLI11: builds
# regbench-train-portable (portable/) against that PyTorch's LibTorch and runs it on the GPU.
#
#   scripts/gpu_train.sh BUNDLE OUT_DIR MINUTES|until:UNIX_TIME [DEPS_PREFIX] [-- TRAIN_FLAGS...]
#
# BUNDLE: written where regbench is installed, `regbench train --model M ... --write-bundle F`.
# MINUTES: training wall time; until:T ends training (with its final validation) by unix time T,
# whatever the build took. DEPS_PREFIX: where Eigen 3, nanoflann and nlohmann-json are installed
# (include/ and share/ with their CMake files, e.g. a copy of Debian's /usr files) when the
# machine has none. TRAIN_FLAGS go to regbench-train-portable (e.g. --resume, --threads 8).
# The run directory OUT_DIR is what `regbench train` writes; copy it back and use it as any
# checkpoint (it loads on CPU builds) or resume it there with `regbench train --resume`.
set -euo pipefail
bundle=${1:?usage: gpu_train.sh BUNDLE OUT_DIR MINUTES|until:UNIX_TIME [DEPS_PREFIX] [-- FLAGS]}
out=${2:?OUT_DIR missing}
budget=${3:?MINUTES missing}
deps=${4:-}
shift $(( $# < 4 ? $# : 4 ))
[ "${1:-}" = "--" ] && shift
src=$(cd "$(dirname "$0")/.." && pwd)
build=${REGBENCH_GPU_BUILD:-/tmp/regbench-gpu-build}
[ -f "$bundle" ] || { echo "gpu_train.sh: bundle $bundle does not exist" >&2; exit 1; }

torch_prefix=$(python3 -c 'import torch; print(torch.utils.cmake_prefix_path)')
torch_include=$(python3 -c 'from torch.utils.cpp_extension import include_paths; print(" ".join("-I" + p for p in include_paths()))')
# C++17, as everywhere else, unless this LibTorch's headers need a newer standard.
std=17
echo '#include <torch/torch.h>' > "${TMPDIR:-/tmp}/regbench_std_probe.cpp"
# shellcheck disable=SC2086
if ! c++ -std=c++17 -fsyntax-only $torch_include "${TMPDIR:-/tmp}/regbench_std_probe.cpp"; then
    std=20
    echo "gpu_train.sh: this LibTorch's headers need C++20; building with -std=c++20" >&2
fi
cmake -S "$src" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DREGBENCH_WITH_LIBS=OFF \
      -DREGBENCH_BUILD_TESTS=OFF -DREGBENCH_BUILD_BENCH=OFF -DREGBENCH_PYTHON=OFF \
      -DCMAKE_CXX_STANDARD="$std" -DCMAKE_PREFIX_PATH="$torch_prefix${deps:+;$deps}"
cmake --build "$build" -j"$(nproc)" --target regbench-train-portable

case "$budget" in
    until:*) minutes=$(python3 -c "import time; print(max(0.5, (${budget#until:} - time.time()) / 60))") ;;
    *) minutes=$budget ;;
esac
echo "gpu_train.sh: training for $minutes minutes" >&2
export LD_LIBRARY_PATH="$(python3 -c 'import os, torch; print(os.path.join(os.path.dirname(torch.__file__), "lib"))')${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
"$build/portable/regbench-train-portable" "$bundle" --out "$out" --device cuda \
    --minutes "$minutes" "$@"
