#!/usr/bin/env bash
# The main job (scripts/main_job.sh: install_deps.sh --main) and the test command
# (scripts/test.sh: the full list) configure one build folder, build/, through
# scripts/build.sh. What build.sh passes to cmake besides the flags must not depend on which of
# the two installed the packages: a tool scripts/build_env.sh probes with `command -v` (ccache,
# which becomes CMAKE_<LANG>_COMPILER_LAUNCHER) and only the full list installed changed every
# compile command, so the test command recompiled everything the main job had built.
# Usage: build_config_same.sh SOURCE_DIR. Names each probed tool the --main list lacks; exit 1.
set -uo pipefail
cd "${1:?usage: build_config_same.sh SOURCE_DIR}" || exit 2
# The --main list: the PACKAGES=( ... ) array, before the lists added for the other modes.
main=$(sed -n '/^PACKAGES=(/,/^)/p' scripts/install_deps.sh | tr -s ' \n()' '\n')
probed=$(grep -o 'command -v [A-Za-z0-9_.+-]*' scripts/build_env.sh scripts/build.sh |
         awk '{print $3}' | sort -u)
if [ -z "$probed" ]; then
  echo "build_config_same: found no 'command -v' probe in scripts/build_env.sh (test outdated?)"
  exit 1
fi
status=0
for tool in $probed; do
  if ! grep -qx "$tool" <<<"$main"; then
    echo "scripts/build_env.sh probes '$tool', which install_deps.sh --main (the main job)" \
         "does not install: the test command's configure would differ from the main job's"
    status=1
  fi
done
exit $status
