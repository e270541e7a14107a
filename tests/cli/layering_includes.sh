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
  "networks:gmm core"
  "baselines:networks gmm core"
  "runners:baselines protocols core"
  "reports:runners/result_row.hpp protocols/pair.hpp core"
  "experiments:reports runners datasets protocols baselines networks core"
  "app:experiments reports runners datasets protocols baselines networks gmm core"
  "portable:experiments/training_bundle.hpp protocols networks core"
  "python:reports runners protocols core"
  "fuzz:experiments runners networks datasets protocols core"
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
    # A family's tests live in its folder (networks/families/<family>/*_test.cpp) and use the
    # shared test helpers.
    case "$file:$top" in *_test.cpp:tests) continue ;; esac
    echo "FAIL: $file includes $target ($folder/ may include: ${entry#*:})" >&2
    status=1
  done < <(grep -rnE '^#include "[a-z_]+/' "$folder" --include='*.cpp' --include='*.hpp')
done
# LibTorch stays inside networks/ (docs/layout.md): other folders include only the networks/ headers
# that name no LibTorch type, and those headers include no LibTorch header and, of networks/,
# only each other.
torch_free=" networks/checkpoint/authors_checkpoint.hpp networks/checkpoint/checkpoint.hpp
  networks/checkpoint/checkpoint_json.hpp networks/checkpoint/import_settings.hpp
  networks/cost.hpp networks/family.hpp networks/gemm_floor.hpp networks/inference.hpp
  networks/training/recipes.hpp networks/training/sample.hpp networks/training/train.hpp
  networks/zoo.hpp "
torch_free_include() {  # is $1 one of torch_free?
  case "$torch_free" in *" $1 "*|*" $1"$'\n'*|*$'\n'"  $1 "*|*$'\n'"  $1"$'\n'*) return 0 ;; esac
  return 1
}
while IFS= read -r line; do
  file="${line%%:*}"
  target="${line#*#include [\"<]}"
  target="${target%%[\">]*}"
  case "$target" in
    networks/*) torch_free_include "$target" && continue ;;
  esac
  echo "FAIL: $file includes $target (outside networks/ only its LibTorch-free headers)" >&2
  status=1
done < <(grep -rnE '^#include (<(torch|ATen|c10)/|"networks/)' app baselines experiments runners \
           reports datasets protocols gmm core python portable --include='*.cpp' --include='*.hpp')
for header in $torch_free; do
  while IFS= read -r line; do
    target="${line#*#include [\"<]}"
    target="${target%%[\">]*}"
    case "$target" in networks/*) torch_free_include "$target" && continue ;; esac
    echo "FAIL: $header (included outside networks/) includes $target (LibTorch or a" \
         "networks/ header that is not LibTorch-free)" >&2
    status=1
  done < <(grep -E '^#include (<(torch|ATen|c10)/|"networks/)' "$header")
done
[ "$status" -eq 0 ] && echo "ok: ${#allowed[@]} folders include only what docs/layout.md allows"
exit "$status"
