#!/usr/bin/env bash
# Scaling series through the product itself: one `complete`-protocol pair per size (CGAL test
# meshes, independent samples, rotation up to 30 deg per axis), each method once with one
# thread; prints size, method, CPU seconds, wall seconds, rre and stop reason from the rows.
# Usage: bench/scaling.sh [sizes] [methods] [params-json]
#   bench/scaling.sh "1000 4000 16000 64000 256000" cpd,gmmreg,svr
# Timings are `cpu_seconds` (thread CPU time of the Align call): valid on a loaded machine.
set -euo pipefail
root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
exe="${REGBENCH:-$root/build/app/regbench}"
sizes="${1:-1000 4000 16000 64000 256000}"
methods="${2:-cpd,gmmreg,svr,filterreg,icp,fgr,ndt}"
params="${3:-{\}}"
out="${SCALING_OUT:-$root/out/scaling}"
timeout="${SCALING_TIMEOUT:-1800}"
mkdir -p "$out"
for n in $sizes; do
  pairs="$out/complete_$n.h5"
  [ -f "$pairs" ] || "$exe" generate --protocol complete --dataset cgal --split test --pairs 1 \
      --points "$n" --max-rotation-deg 30 --seed 1 --out "$pairs" --data-dir "$root/data" >/dev/null
  tag="$(echo "$methods$params" | md5sum | cut -c1-8)"
  rows="$out/rows_${n}_$tag.jsonl"
  # --max-points 0: the series measures the methods at full size (no scale guard).
  "$exe" run -q --threads 1 --jobs 1 --timeout "$timeout" --max-points 0 --pairs "$pairs" \
      --methods "$methods" --params "$params" --out "$rows"
  /usr/bin/python3 - "$rows" "$n" <<'PY'
import json, sys
for line in open(sys.argv[1]):
    r = json.loads(line)
    print(f"{sys.argv[2]:>7} {r['method']:<10} cpu {r.get('cpu_seconds', 0):9.3f} s  "
          f"wall {r['seconds']:9.3f} s  rre {r['metrics']['rre']:7.3f} deg  "
          f"{r['status']} {r['stop_reason']}", flush=True)
PY
done
