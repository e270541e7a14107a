# Sourced by scripts/build.sh and scripts/ci_extra.sh: the settings every regbench build shares.
# Expects $root (the repository root); sets $jobs and the cmake arguments in the $launcher array.
jobs="${REGBENCH_BUILD_JOBS:-$(nproc)}"
launcher=()
# ccache (when installed) makes rebuilds and several worktrees cheap; CCACHE_BASEDIR lets
# worktrees at different paths share hits.
if command -v ccache >/dev/null 2>&1; then
  launcher=(-DCMAKE_CXX_COMPILER_LAUNCHER=ccache -DCMAKE_C_COMPILER_LAUNCHER=ccache)
  export CCACHE_BASEDIR="${CCACHE_BASEDIR:-$(dirname "$root")}"
fi
