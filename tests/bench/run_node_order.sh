#!/usr/bin/env bash
# `torsion run` on a mesh in a scattered order (scatter_mesh.sh: a mesher's insertion order),
# renumbered inside (node_order "cache_friendly", the default) and kept in the file's order
# (node_order "file"), beside the committed mesh (already in reverse Cuthill-McKee order), and
# Bullet's explicit solver (tet4, one thread: it has neither tet10 nor threads) on the scattered
# mesh: wall and process CPU time (user + system) of the whole run and the median step time of
# summary.json, interleaved REPS times (docs/performance.md, "Node order").
#   tests/bench/run_node_order.sh [SCENE=tests/bench/twist_cylinder_8332_run.json] [REPS=5]
#       [ELEMENT=tet4] [THREADS=1]  (env: BUILD=build, BULLET_SUBSTEPS=2; empty: no Bullet row)
set -euo pipefail
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
SCENE=${1:-$ROOT/tests/bench/twist_cylinder_8332_run.json}
REPS=${2:-5}
ELEMENT=${3:-tet4}
THREADS=${4:-1}
BUILD=${BUILD:-$ROOT/build}
BULLET_SUBSTEPS=${BULLET_SUBSTEPS-2}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

mesh=$(python3 -c 'import json, os, sys; s = json.load(open(sys.argv[1]))
print(os.path.normpath(os.path.join(os.path.dirname(os.path.abspath(sys.argv[1])), s["bodies"][0]["mesh"])))' "$SCENE")
"$ROOT/tests/bench/scatter_mesh.sh" "$mesh" "$work/scattered.node"
scene() {  # scene() MESH NODE_ORDER OUT.json
  python3 - "$SCENE" "$1" "$2" "$ELEMENT" "$3" <<'PY'
import json, sys
s = json.load(open(sys.argv[1]))
b = s["bodies"][0]
b["mesh"], b["node_order"], b["element"] = sys.argv[2], sys.argv[3], sys.argv[4]
json.dump(s, open(sys.argv[5], "w"))
PY
}
scene "$mesh" cache_friendly "$work/committed.json"
scene "$work/scattered.node" cache_friendly "$work/renumbered.json"
scene "$work/scattered.node" file "$work/file.json"

times() {  # "wall s / CPU s" of a command's whole process (CPU: user + system)
  /usr/bin/time -f "%e %U %S" "$@" 2>&1 >/dev/null | tail -1 | awk '{ printf "%.2f / %.2f", $1, $2 + $3 }'
}
echo "machine: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | sed 's/^ //'), nproc $(nproc)"
echo "commit: $(git -C "$ROOT" rev-parse --short HEAD), scene $(basename "$SCENE"), $ELEMENT, $THREADS thread(s)"
echo "load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
echo "rep | committed mesh: wall s / CPU s, step ms | scattered, renumbered | scattered, file order | Bullet explicit, scattered: wall s / CPU s"
for rep in $(seq "$REPS"); do
  row="$rep"
  for case in committed renumbered file; do
    s=$(times "$BUILD/demos/torsion" run "$work/$case.json" --out "$work/out_$case" --threads "$THREADS")
    ms=$(python3 -c 'import json, sys; print("%.3f" % json.load(open(sys.argv[1]))["ms_per_step"]["median"])' "$work/out_$case/summary.json")
    row="$row | $s, $ms"
  done
  if [[ -n $BULLET_SUBSTEPS ]]; then
    row="$row | $(times "$BUILD/tests/bench/bench_twist" --solver bullet-explicit --mesh "$work/scattered.node" --substeps "$BULLET_SUBSTEPS")"
  fi
  echo "$row"
done
echo "load at end: $(cut -d' ' -f1-3 /proc/loadavg)"
