# Sourced by scripts/build.sh and scripts/ci_extra.sh: the settings every regbench build shares.
# Expects $root (the repository root); sets $jobs and the cmake arguments in the $launcher array.
jobs="${REGBENCH_BUILD_JOBS:-$(nproc)}"
launcher=()
# ccache (when installed) makes rebuilds and several worktrees cheap; CCACHE_BASEDIR lets
# worktrees at different paths share hits. scripts/install_deps.sh installs it in every mode
# (--main too), so the main job and the test command configure build/ with the same launcher
# and the second reuses the first's objects (tests/cli/build_config_same.sh).
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
  # The sanitizer build uses -gline-tables-only; with -g ccache also hashes the working
  # directory unless told not to, so a fresh clone elsewhere missed every object (measured:
  # 710 s for the sanitizer build of a fresh clone next to a warm cache).
  export CCACHE_NOHASHDIR="${CCACHE_NOHASHDIR:-1}"
fi
