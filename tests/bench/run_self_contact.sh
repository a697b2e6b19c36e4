#!/usr/bin/env bash
# The plectoneme's self-contact figures of docs/performance-contact.md ("Self-contact on the
# plectoneme rod") in one command: the whole scene with self-contact on and off (steps/s, CPU per
# step, the searches' wall time per step, Newton iterations, unconverged steps, end penetration,
# crossings), then its contact phase alone (steps 2801-3200, from a checkpoint the first run saves).
#
# Usage: bash tests/bench/run_self_contact.sh RESULTS_DIR
# Environment (defaults in brackets):
#   BUILD    build directory with tests/bench/bench_self_contact [build]
#   THREADS  worker threads [2]
# Writes RESULTS_DIR/machine.txt (load, commit) and RESULTS_DIR/raw.jsonl (one line per run).
set -euo pipefail
if [[ $# -ne 1 ]]; then sed -n '2,11p' "$0"; exit 2; fi
OUT=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BUILD=${BUILD:-$ROOT/build}
THREADS=${THREADS:-2}
B=$BUILD/tests/bench/bench_self_contact
[[ -x $B ]] || { echo "missing $B (cmake --build $BUILD --target bench_self_contact)" >&2; exit 2; }
SCENE=$ROOT/demos/scenes/plectoneme.json
mkdir -p "$OUT"
{
  echo "date: $(date -u +%FT%TZ)"
  echo "commit: $(git -C "$ROOT" rev-parse --short HEAD)$(git -C "$ROOT" diff --quiet || echo ' (plus uncommitted changes)')"
  echo "load at start: $(uptime)"
} >"$OUT/machine.txt"
RAW=$OUT/raw.jsonl
: >"$RAW"
# The checkpoint keeps the solver's settings: the contact phase runs with the build's own.
"$B" "$SCENE" --threads "$THREADS" --check-every 100 --save-at 2800 "$OUT/at2800.ckpt" >>"$RAW"
"$B" "$SCENE" --threads "$THREADS" --check-every 100 --self-contact off >>"$RAW"
"$B" "$SCENE" --threads "$THREADS" --check-every 100 --resume "$OUT/at2800.ckpt" --steps 400 >>"$RAW"
"$B" "$SCENE" --threads "$THREADS" --check-every 100 --resume "$OUT/at2800.ckpt" --steps 400 \
    --self-contact off >>"$RAW"
echo "load at end: $(uptime)" >>"$OUT/machine.txt"
cat "$RAW"
