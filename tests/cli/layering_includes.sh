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
  "portable:experiments/training_bundle.hpp protocols ogmm core"
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
# LibTorch stays inside ogmm/ (docs/layout.md): other folders include only the ogmm/ headers
# that name no LibTorch type, and those headers include no LibTorch header nor another of ogmm/.
torch_free=" ogmm/authors_checkpoint.hpp ogmm/checkpoint.hpp ogmm/checkpoint_json.hpp ogmm/cost.hpp
  ogmm/family.hpp ogmm/gemm_floor.hpp ogmm/inference.hpp ogmm/train.hpp ogmm/zoo.hpp "
while IFS= read -r line; do
  file="${line%%:*}"
  target="${line#*#include [\"<]}"
  target="${target%%[\">]*}"
  case "$target" in
    ogmm/*) case "$torch_free" in *" $target "*|*" $target"$'\n'*) continue ;; esac ;;
  esac
  echo "FAIL: $file includes $target (outside ogmm/ only its LibTorch-free headers)" >&2
  status=1
done < <(grep -rnE '^#include (<(torch|ATen|c10)/|"ogmm/)' app baselines experiments runners \
           reports datasets protocols gmm core python portable --include='*.cpp' --include='*.hpp')
for header in $torch_free; do
  if grep -nE '^#include (<(torch|ATen|c10)/|"ogmm/)' "$header" >&2; then
    echo "FAIL: $header (included outside ogmm/) includes LibTorch or another ogmm/ header" >&2
    status=1
  fi
done
[ "$status" -eq 0 ] && echo "ok: ${#allowed[@]} folders include only what docs/layout.md allows"
exit "$status"
