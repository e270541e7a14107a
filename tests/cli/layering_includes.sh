#!/usr/bin/env bash
# Layering check on the sources: each folder includes only itself and the folders below it in
# the picture of docs/layout.md (no back-arrows). reports/ reads and renders result rows only:
# of runners/ it may include result_row.hpp, of protocols/ the header-only Pair struct (the
# HTML report draws pairs), nothing of datasets/, baselines/ or pair generation.
# Usage: layering_includes.sh SOURCE_DIR. Prints one line per forbidden include, naming the
# file, and exits 1 if there is any.
set -uo pipefail
cd "${1:?usage: layering_includes.sh SOURCE_DIR}" || exit 2
# folder: the folders it may include (besides itself)
allowed=(
  "core:"
  "gmm:core"
  "protocols:core"
  "datasets:protocols core"
  "ogmm:gmm core"
  "baselines:ogmm gmm core"
  "runners:baselines protocols core"
  "reports:runners/result_row.hpp protocols/pair.hpp core"
  "experiments:reports runners datasets protocols baselines ogmm core"
  "app:experiments reports runners datasets protocols baselines ogmm gmm core"
)
status=0
for entry in "${allowed[@]}"; do
  folder="${entry%%:*}"
  ok=" $folder ${entry#*:} "
  while IFS= read -r line; do
    file="${line%%:*}"
    target="${line#*#include \"}"
    target="${target%%\"*}"
    top="${target%%/*}"
    case "$ok" in
      *" $top "*|*" $target "*) continue ;;
    esac
    echo "FAIL: $file includes $target ($folder/ may include: ${entry#*:})" >&2
    status=1
  done < <(grep -rnE '^#include "[a-z_]+/' "$folder" --include='*.cpp' --include='*.hpp')
done
[ "$status" -eq 0 ] && echo "ok: ${#allowed[@]} folders include only what docs/layout.md allows"
exit "$status"
