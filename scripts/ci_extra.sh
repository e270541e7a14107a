#!/usr/bin/env bash
# CI extras after the main test suite (scripts/test.sh runs this):
#  1. an AddressSanitizer + UndefinedBehaviorSanitizer build with clang in build-san/ (no
#     networks/, no benchmarks; LibTorch only for fuzz_torch_save) and its test suite: core,
#     protocols, baselines, runners, reports, app and the CLI reliability scenarios (the Slurm test runs in the main build only);
#  2. every libFuzzer target (fuzz/) on a copy of its seed corpus fuzz/corpus/<name>/, with a
#     fixed seed and a fixed number of inputs (REGBENCH_FUZZ_RUNS, default 20000) capped at
#     REGBENCH_FUZZ_SECONDS (default 60) of wall time: the same binary explores the same inputs on
#     every machine, so CI is a reproducible regression gate, not a lottery. For exploratory
#     fuzzing set REGBENCH_FUZZ_RUNS=-1 (unbounded; then only the time cap applies) and
#     REGBENCH_FUZZ_SEED to anything else. A crash stops CI and leaves the input in
#     build-san/fuzz-artifacts/; turn it into a regression test (tests/protocols/ or
#     tests/datasets/) and add the input to the seed corpus.
# REGBENCH_SKIP_EXTRA=1 skips all of it.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
if [ "${REGBENCH_SKIP_EXTRA:-0}" = 1 ]; then
  echo "[ci_extra] skipped (REGBENCH_SKIP_EXTRA=1)"
  exit 0
fi
build="${REGBENCH_SAN_BUILD_DIR:-$root/build-san}"
seconds="${REGBENCH_FUZZ_SECONDS:-60}"
runs="${REGBENCH_FUZZ_RUNS:-20000}"
fuzz_seed="${REGBENCH_FUZZ_SEED:-1}"
# shellcheck source=scripts/build_env.sh
source "$root/scripts/build_env.sh"
start=$(date +%s)
# -O1 with line tables only (the sanitizers' usual setting: stack traces keep file:line) compiles
# the Open3D/PCL/CGAL-heavy sources much faster than RelWithDebInfo's -O2 -g.
san_flags="-O1 -gline-tables-only -DNDEBUG"
cmake -S "$root" -B "$build" -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_C_FLAGS_RELWITHDEBINFO="$san_flags" -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="$san_flags" \
  -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ "${launcher[@]}" \
  -DREGBENCH_SANITIZE=ON -DREGBENCH_FUZZ=ON -DREGBENCH_WITH_TORCH=OFF -DREGBENCH_BUILD_BENCH=OFF
cmake --build "$build" -j "$jobs"
t_build=$(date +%s)

# Sanitizer settings, each with its reason:
# - detect_container_overflow=0: Open3D, PCL and HDF5 are prebuilt without ASan; std::vector
#   objects crossing into them carry no container annotations, which ASan misreports as
#   container overflows.
# - LSan suppressions (scripts/sanitizers/lsan.supp): one-time allocations that prebuilt
#   libraries keep until exit (OpenMP thread pools, HDF5's global tables).
# - allocator_may_return_null=1: corrupt HDF5 headers make libhdf5 itself request absurd sizes
#   (2^53 bytes, found by fuzz_pair_file); glibc returns NULL there and HDF5 reports an error,
#   which is what regbench relies on. ASan would abort instead.
export ASAN_OPTIONS="detect_container_overflow=0:allocator_may_return_null=1"
export LSAN_OPTIONS="suppressions=$root/scripts/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
(cd "$build" && ctest --output-on-failure -j "$(nproc)" --timeout 900 -E 'cli_slurm')
t_tests=$(date +%s)

artifacts="$build/fuzz-artifacts"
mkdir -p "$artifacts"
for name in off ply pcd xyz xyz_import pair_file result_rows checkpoint_json pair_attributes torch_save experiment_file; do
  corpus="$(mktemp -d)"
  cp -r "$root/fuzz/corpus/$name/." "$corpus/"
  # pair_attributes writes an HDF5 file and reads it in a forked child for every input (about
  # 30 inputs/s, like pair_file): 600 inputs keep it near 20 s of the CI time.
  target_runs="$runs"
  if [ "$name" = pair_attributes ] && [ "$runs" -gt 600 ]; then target_runs=600; fi
  echo "[ci_extra] fuzz_$name: seed $fuzz_seed, $target_runs inputs, at most ${seconds}s"
  if ! "$build/fuzz/fuzz_$name" -seed="$fuzz_seed" -runs="$target_runs" -max_total_time="$seconds" \
    -timeout=10 -rss_limit_mb=2048 \
    -artifact_prefix="$artifacts/${name}-" -print_final_stats=1 "$corpus" \
    >"$artifacts/$name.log" 2>&1; then
    tail -40 "$artifacts/$name.log"
    echo "[ci_extra] fuzz_$name found a crash; input saved under $artifacts/" >&2
    exit 1
  fi
  grep -E "stat::number_of_executed_units|stat::peak_rss_mb" "$artifacts/$name.log" | tr '\n' ' '
  echo
  rm -rf "$corpus"
done
t_fuzz=$(date +%s)
echo "[ci_extra] sanitizer build $((t_build - start)) s, sanitizer tests $((t_tests - t_build)) s," \
  "fuzzing $((t_fuzz - t_tests)) s"
