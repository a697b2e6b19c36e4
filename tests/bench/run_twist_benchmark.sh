#!/usr/bin/env bash
# Cylinder-twist benchmark: our solver beside Bullet's btDeformableMultiBodyDynamicsWorld, every
# configuration in one run, interleaved, repeated. One bench_twist process per configuration (so
# each peak RSS is that configuration's own). Writes to RESULTS_DIR:
#   machine.txt      nproc, CPU model, kernel, load, git revision, the command and settings
#   search.jsonl     the explicit-substep search (every trial)
#   raw.jsonl        one JSON line per timed run (bench_twist output + case/config/rep)
#   runs.csv         the same, flattened
#   summary.csv      median over repetitions per (case, configuration)
#   summary.md       the same as Markdown tables
#
# Usage: tests/bench/run_twist_benchmark.sh RESULTS_DIR
# Environment (defaults in brackets):
#   BENCH_TWIST   bench_twist binary [build-bench/tests/bench/bench_twist]
#   MESH_DIR      directory of cylinder_<tets>.node/.ele [assets/meshes]
#   SIZES         E = 1e5 meshes ["2430 4323 8332 31558"]
#   E_SWEEP_SIZE  mesh also run at the E_SWEEP moduli [8332]
#   E_SWEEP       ["1e6 1e7"]
#   REPS          repetitions [3]
#   REPS_LARGE    repetitions for the LARGE_SIZE mesh [1]
#   LARGE_SIZE    [31558]; CHOLMOD and the CG tolerance sweep are not run on it
#   REPS_SWEEP    repetitions for the E_SWEEP cases [REPS]
#   BULLET_RELAXED_TOL  relaxed btConjugateGradient tolerance, identity preconditioner [1e-4]
#   BULLET_PC_TOL       tolerance of the mass-preconditioned row [1e-5]
#                 (both chosen so Bullet's deviation from its own exactly solved trajectory is at
#                 most ours at tolerance 1e-4; see tests/bench/README_twist.md)
#   TOLERANCE_SWEEP_SIZES  sizes that also run our CG at 1e-3 and 1e-6 [8332]
#   CHOLMOD_MAX_TETS  skip CHOLMOD above this many tets [10000]
#   STEPS         override the step count (quick tests only; the protocol is 600) []
#   SUBSTEP_LIST  explicit substeps tried in order ["1 2 3 4 6 8 12 16 24 32 48 64 96 128 192 256"]
set -euo pipefail

if [[ $# -ne 1 ]]; then
  sed -n '2,30p' "$0"
  exit 2
fi
RESULTS_DIR=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BENCH_TWIST=${BENCH_TWIST:-$ROOT/build-bench/tests/bench/bench_twist}
MESH_DIR=${MESH_DIR:-$ROOT/assets/meshes}
SIZES=${SIZES:-"2430 4323 8332 31558"}
E_SWEEP_SIZE=${E_SWEEP_SIZE:-8332}
E_SWEEP=${E_SWEEP:-"1e6 1e7"}
REPS=${REPS:-3}
REPS_LARGE=${REPS_LARGE:-1}
LARGE_SIZE=${LARGE_SIZE:-31558}
REPS_SWEEP=${REPS_SWEEP:-$REPS}
BULLET_RELAXED_TOL=${BULLET_RELAXED_TOL:-1e-4}
BULLET_PC_TOL=${BULLET_PC_TOL:-1e-5}
TOLERANCE_SWEEP_SIZES=${TOLERANCE_SWEEP_SIZES:-8332}
CHOLMOD_MAX_TETS=${CHOLMOD_MAX_TETS:-10000}
STEPS=${STEPS:-}
SUBSTEP_LIST=${SUBSTEP_LIST:-"1 2 3 4 6 8 12 16 24 32 48 64 96 128 192 256"}

[[ -x $BENCH_TWIST ]] || { echo "no bench_twist at $BENCH_TWIST (build target bench_twist)" >&2; exit 2; }
command -v python3 >/dev/null || { echo "python3 is needed for the summary" >&2; exit 2; }
mkdir -p "$RESULTS_DIR"
RAW=$RESULTS_DIR/raw.jsonl
SEARCH=$RESULTS_DIR/search.jsonl
: >"$RAW"
: >"$SEARCH"
STEP_ARGS=()
[[ -n $STEPS ]] && STEP_ARGS=(--steps "$STEPS")

{
  echo "date: $(date -Is)"
  echo "command: $0 $*"
  echo "nproc: $(nproc)"
  echo "cpu: $(lscpu | sed -n 's/^Model name:[[:space:]]*//p' | head -1)"
  echo "kernel: $(uname -sr)"
  echo "load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "git: $(git -C "$ROOT" rev-parse --short HEAD 2>/dev/null) $(git -C "$ROOT" status --porcelain 2>/dev/null | wc -l) changed files"
  echo "binary: $BENCH_TWIST (built $(date -Is -r "$BENCH_TWIST"))"
  echo "settings: SIZES='$SIZES' E_SWEEP_SIZE=$E_SWEEP_SIZE E_SWEEP='$E_SWEEP' REPS=$REPS REPS_LARGE=$REPS_LARGE REPS_SWEEP=$REPS_SWEEP"
  echo "          BULLET_RELAXED_TOL=$BULLET_RELAXED_TOL BULLET_PC_TOL=$BULLET_PC_TOL TOLERANCE_SWEEP_SIZES='$TOLERANCE_SWEEP_SIZES' CHOLMOD_MAX_TETS=$CHOLMOD_MAX_TETS STEPS='$STEPS'"
} >"$RESULTS_DIR/machine.txt"

# Cases: "size E".
CASES=()
for s in $SIZES; do CASES+=("$s 1e5"); done
for e in $E_SWEEP; do CASES+=("$E_SWEEP_SIZE $e"); done

mesh_of() { echo "$MESH_DIR/cylinder_$1.node"; }

# Explicit corotated: the smallest substep count that stays stable over the whole protocol
# (no NaN, no node faster than 100 m/s, finite angle errors).
declare -A SUBSTEPS
for c in "${CASES[@]}"; do
  read -r size E <<<"$c"
  mesh=$(mesh_of "$size")
  [[ -f $mesh ]] || { echo "missing mesh $mesh" >&2; exit 2; }
  found=""
  for s in $SUBSTEP_LIST; do
    line=$(OMP_NUM_THREADS=1 "$BENCH_TWIST" --solver bullet-explicit --mesh "$mesh" --E "$E" --substeps "$s" "${STEP_ARGS[@]}" \
             --label "search $size $E")
    echo "$line" >>"$SEARCH"
    ok=$(python3 -c 'import json,sys,math; j=json.loads(sys.argv[1]); print(int(j["stable"] and all(x["error"] is not None for x in j["slices"])))' "$line")
    echo "search: cylinder_$size E=$E substeps=$s stable=$ok" >&2
    if [[ $ok == 1 ]]; then found=$s; break; fi
  done
  SUBSTEPS[$c]=${found:-none}
done

# Configurations of one case: "config-name|bench_twist arguments".
configs_of() {
  local size=$1 E=$2 tets
  echo "torsion-cg tol=1e-4 t1|--solver torsion-cg --tolerance 1e-4 --threads 1"
  echo "torsion-cg tol=1e-4 t2|--solver torsion-cg --tolerance 1e-4 --threads 2"
  if [[ " $TOLERANCE_SWEEP_SIZES " == *" $size "* && $E == 1e5 ]]; then
    echo "torsion-cg tol=1e-3 t1|--solver torsion-cg --tolerance 1e-3 --threads 1"
    echo "torsion-cg tol=1e-6 t1|--solver torsion-cg --tolerance 1e-6 --threads 1"
  fi
  tets=$size
  if (( tets <= CHOLMOD_MAX_TETS )) && [[ $size != "$LARGE_SIZE" ]]; then
    echo "torsion-cholmod t1|--solver torsion-cholmod --threads 1"
  fi
  echo "bullet-implicit default|--solver bullet-implicit"
  echo "bullet-implicit tol=$BULLET_RELAXED_TOL|--solver bullet-implicit --tolerance $BULLET_RELAXED_TOL"
  echo "bullet-implicit mass-pc tol=$BULLET_PC_TOL|--solver bullet-implicit --tolerance $BULLET_PC_TOL --mass-preconditioner"
  local s=${SUBSTEPS["$size $E"]}
  if [[ $s != none ]]; then
    echo "bullet-explicit substeps=$s|--solver bullet-explicit --substeps $s"
  fi
}

reps_of() {  # size E
  if [[ $1 == "$LARGE_SIZE" ]]; then echo "$REPS_LARGE"; elif [[ $2 != 1e5 ]]; then echo "$REPS_SWEEP"; else echo "$REPS"; fi
}
max_reps=$REPS
(( REPS_LARGE > max_reps )) && max_reps=$REPS_LARGE
(( REPS_SWEEP > max_reps )) && max_reps=$REPS_SWEEP
for ((rep = 1; rep <= max_reps; rep++)); do
  # Every configuration of every case in one pass; the order rotates from one repetition to the
  # next so that no configuration always runs first or right after the same neighbour.
  JOBS=()
  for c in "${CASES[@]}"; do
    read -r size E <<<"$c"
    (( rep <= $(reps_of "$size" "$E") )) || continue
    while IFS= read -r cfg; do JOBS+=("$size|$E|$cfg"); done < <(configs_of "$size" "$E")
  done
  n=${#JOBS[@]}
  for ((k = 0; k < n; k++)); do
    job=${JOBS[$(((k + (rep - 1) * (n / max_reps + 1)) % n))]}
    IFS='|' read -r size E name args <<<"$job"
    mesh=$(mesh_of "$size")
    threads=1
    [[ $args == *"--threads 2"* ]] && threads=2
    # OMP_NUM_THREADS: CHOLMOD runs its supernodal factorisation on OpenMP; match our thread count.
    # shellcheck disable=SC2086
    line=$(OMP_NUM_THREADS=$threads "$BENCH_TWIST" $args --mesh "$mesh" --E "$E" "${STEP_ARGS[@]}" --label "$name") || line='{"status":"crashed"}'
    python3 -c 'import json,sys; j=json.loads(sys.argv[1]); j.update(case_size=int(sys.argv[2]), case_E=float(sys.argv[3]), config=sys.argv[4], rep=int(sys.argv[5])); print(json.dumps(j))' \
      "$line" "$size" "$E" "$name" "$rep" >>"$RAW"
    echo "rep $rep [$((k + 1))/$n] cylinder_$size E=$E $name: $(python3 -c 'import json,sys; j=json.loads(sys.argv[1]); print(j.get("status"), "%.1f steps/s" % (j.get("steps_per_s") or 0))' "$line")" >&2
  done
done
echo "load at end: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$RESULTS_DIR/machine.txt"

python3 "$ROOT/tests/bench/summarize_twist.py" "$RESULTS_DIR"
