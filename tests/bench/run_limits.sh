#!/usr/bin/env bash
# The performance-limits table in one command: every row of docs/performance.md ("Limits table")
# beside Bullet's btDeformableMultiBodyDynamicsWorld on the same mesh, in one run, plus the
# machine's roofline ceilings. A short protocol (default 100 ramp + 100 hold steps of the
# cylinder twist) so the whole table takes a few minutes on 2 cores.
#
# Usage: bash tests/bench/run_limits.sh RESULTS_DIR
# Environment (defaults in brackets):
#   BUILD        build directory with bench_twist, bench_bullet_demos, machine_probe, torsion [build]
#   STEPS, RAMP  twist protocol: total steps and ramp steps [200, 100]
#   BIG_TETS     tets of the generated large cylinder [125000]
#   BIG_MESH_DIR where it is generated (kept between runs) [RESULTS_DIR]
#   BULLET_BIG_STEPS  Bullet runs only the first steps of the protocol on the large mesh [20]
#   BULLET_SLOW_STEPS  ...and on the 31558 mesh and at E = 1e7 (3-4 steps/s) [60]
# Writes RESULTS_DIR/machine.txt (machine, load, commit, command), machine_probe.json,
# raw.jsonl (one line per run), summary.md (the table).
set -euo pipefail
if [[ $# -ne 1 ]]; then sed -n '2,15p' "$0"; exit 2; fi
OUT=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
STEPS=${STEPS:-200}
RAMP=${RAMP:-100}
BIG_TETS=${BIG_TETS:-125000}
BULLET_BIG_STEPS=${BULLET_BIG_STEPS:-20}
BULLET_SLOW_STEPS=${BULLET_SLOW_STEPS:-60}
BT=$BUILD/tests/bench/bench_twist
for exe in "$BT" "$BUILD/tests/bench/bench_bullet_demos" "$BUILD/tests/bench/machine_probe" \
           "$BUILD/demos/torsion"; do
  [[ -x $exe ]] || { echo "missing $exe (cmake --build $BUILD --target bench_twist bench_bullet_demos machine_probe torsion)" >&2; exit 2; }
done
mkdir -p "$OUT"
RAW=$OUT/raw.jsonl
: >"$RAW"
{
  echo "command: bash tests/bench/run_limits.sh $OUT (STEPS=$STEPS RAMP=$RAMP BIG_TETS=$BIG_TETS BULLET_BIG_STEPS=$BULLET_BIG_STEPS BULLET_SLOW_STEPS=$BULLET_SLOW_STEPS)"
  echo "date: $(date -u +%FT%TZ)"
  echo "commit: $(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet || echo ' (plus uncommitted changes)')"
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), nproc $(nproc), $(free -g | awk '/Mem:/ {print $2}') GiB"
  echo "kernel: $(uname -r)"
  echo "load at start: $(uptime)"
} >"$OUT/machine.txt"

"$BUILD/tests/bench/machine_probe" >"$OUT/machine_probe.json"

# The large cylinder is generated, not committed (tetgen through the project's mesh tool).
BIG=${BIG_MESH_DIR:-$OUT}/cylinder_$BIG_TETS
if [[ ! -f $BIG.node ]]; then
  "$BUILD/demos/torsion" mesh cylinder --radius 1 --length 10 --tets "$BIG_TETS" -o "$BIG.node" \
      >"$OUT/mesh.log" 2>&1
fi

# run ROW ENGINE ARGS...: one bench_twist process, its JSON line tagged with the row.
run() {
  local row=$1; shift
  local engine=$1; shift
  local line
  if line=$("$BT" "$@" 2>>"$OUT/stderr.log"); then
    echo "{\"row\": \"$row\", \"engine\": \"$engine\", \"run\": $line}" >>"$RAW"
  else
    echo "{\"row\": \"$row\", \"engine\": \"$engine\", \"failed\": \"$*\"}" >>"$RAW"
  fi
}
P="--steps $STEPS --ramp-steps $RAMP"
M=$ROOT/assets/meshes
run "tet4 8332, 1 thread" ours --solver torsion-cg --mesh $M/cylinder_8332 --threads 1 $P
# ours-rcm: the same mesh renumbered in reverse Cuthill-McKee order, as `torsion mesh` writes new
# meshes (mesh/node_ordering.h); the committed assets keep tetgen's numbering.
run "tet4 8332, 1 thread" ours-rcm --solver torsion-cg --mesh $M/cylinder_8332 --threads 1 --node-order rcm $P
run "tet4 8332, 1 thread" bullet --solver bullet-implicit --mesh $M/cylinder_8332 $P
run "tet4 31558, 2 threads" ours --solver torsion-cg --mesh $M/cylinder_31558 --threads 2 $P
run "tet4 31558, 2 threads" ours-rcm --solver torsion-cg --mesh $M/cylinder_31558 --threads 2 --node-order rcm $P
run "tet4 31558, 2 threads" bullet --solver bullet-implicit --mesh $M/cylinder_31558 --steps "$BULLET_SLOW_STEPS" --ramp-steps $RAMP
run "tet10 8332, 2 threads" ours --solver torsion-cg --element tet10 --mesh $M/cylinder_8332 --threads 2 $P
run "tet10 8332, 2 threads" ours-rcm --solver torsion-cg --element tet10 --mesh $M/cylinder_8332 --threads 2 --node-order rcm $P
run "tet10 8332, 2 threads" ours-two_level --solver torsion-cg --element tet10 --preconditioner two_level --mesh $M/cylinder_8332 --threads 2 $P
run "tet10 8332, 2 threads" ours-1-thread --solver torsion-cg --element tet10 --mesh $M/cylinder_8332 --threads 1 $P
run "tet4 ${BIG_TETS}, 2 threads" ours --solver torsion-cg --mesh "$BIG" --threads 2 $P
run "tet4 ${BIG_TETS}, 2 threads" bullet --solver bullet-implicit --mesh "$BIG" --steps "$BULLET_BIG_STEPS" --ramp-steps $RAMP
for pc in block_jacobi lagged_cholesky incomplete_cholesky; do
  run "E 1e7 8332, 1 thread" "ours-$pc" --solver torsion-cg --preconditioner $pc --E 1e7 --mesh $M/cylinder_8332 --threads 1 $P
done
run "E 1e7 8332, 1 thread" bullet --solver bullet-implicit --E 1e7 --mesh $M/cylinder_8332 --steps "$BULLET_SLOW_STEPS" --ramp-steps $RAMP
run "fast hand 8332 (+-45 deg at 2 Hz), 1 thread" ours --solver torsion-cg --mesh $M/cylinder_8332 --threads 1 --oscillate-hz 2 --amplitude 0.7853981633974483 --steps $STEPS
run "fast hand 8332 (+-45 deg at 2 Hz), 1 thread" bullet --solver bullet-implicit --mesh $M/cylinder_8332 --oscillate-hz 2 --amplitude 0.7853981633974483 --steps $STEPS
# Drop impact: a scene through both engines' worlds (contact with the ground on both sides).
"$BUILD/tests/bench/bench_bullet_demos" "$ROOT/tests/bench/drop_cylinder_8332.json" \
    >"$OUT/drop.jsonl" 2>>"$OUT/stderr.log" || true
echo "load at end: $(uptime)" >>"$OUT/machine.txt"
/usr/bin/python3 "$ROOT/tests/bench/summarize_limits.py" "$OUT" >"$OUT/summary.md"
cat "$OUT/machine.txt" "$OUT/summary.md"
