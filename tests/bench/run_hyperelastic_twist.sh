#!/usr/bin/env bash
# Cylinder twist with the stable neo-Hookean law on both sides: our Newton step
# (Material::law = kStableNeoHookean) beside Bullet's btDeformableNeoHookeanForce (implicit), with
# our corotated law as the baseline. Same protocol as run_twist_benchmark.sh (E = 1e5, nu = 0.3,
# dt = 0.01 s, pi/2 over 300 steps, 600 steps), one mesh, every configuration interleaved and
# repeated, one bench_twist process each. Writes to RESULTS_DIR:
#   machine.txt      nproc, CPU, load, the settings
#   raw.jsonl        one JSON line per timed run (bench_twist output + config/rep)
#   curves/          per configuration and repetition: step,time,angle,torque (--curve) and the
#                    final positions (--dump-positions)
#   reference.jsonl  the two accuracy references, run once (not timed against the others):
#                    ours neo-Hookean with CG at REF_TOL, and Bullet's neo-Hookean at its default
#                    CG tolerance (SIMD_EPSILON), which is also a timed row
#   summary.md       medians over repetitions (summarize_hyperelastic_twist.py)
#
# Usage: tests/bench/run_hyperelastic_twist.sh RESULTS_DIR
# Environment (defaults in brackets):
#   BENCH_TWIST  bench_twist binary [build-bench/tests/bench/bench_twist]
#   MESH         [assets/meshes/cylinder_8332.node]
#   E            Young's modulus [1e5]
#   REPS         repetitions [3]
#   STEPS        override the step count (the protocol is 600; the ramp stays at 300 unless
#                RAMP_STEPS is set) []
#   RAMP_STEPS   []
#   BULLET_RELAXED_TOL  relaxed btConjugateGradient tolerance, identity preconditioner [1e-4]
#   BULLET_PC_TOL       tolerance of the mass-preconditioned row [1e-5]
#   BULLET_NEWTON2      1: also Bullet with 2 Newton iterations at BULLET_RELAXED_TOL [1]
#   OURS_ONE_NEWTON     1: also ours with newton_tolerance 1e-4 and 1e-3 (one Newton solve per step, like
#                       Bullet's default) [1]
#   REF_TOL      CG and Newton tolerance of our reference run [1e-8]
set -euo pipefail

if [[ $# -ne 1 ]]; then
  sed -n '2,30p' "$0"
  exit 2
fi
RESULTS_DIR=$1
ROOT=$(cd "$(dirname "$0")/../.." && pwd)
BENCH_TWIST=${BENCH_TWIST:-$ROOT/build-bench/tests/bench/bench_twist}
MESH=${MESH:-$ROOT/assets/meshes/cylinder_8332.node}
E=${E:-1e5}
REPS=${REPS:-3}
STEPS=${STEPS:-}
RAMP_STEPS=${RAMP_STEPS:-}
BULLET_RELAXED_TOL=${BULLET_RELAXED_TOL:-1e-4}
BULLET_PC_TOL=${BULLET_PC_TOL:-1e-5}
BULLET_NEWTON2=${BULLET_NEWTON2:-1}
OURS_ONE_NEWTON=${OURS_ONE_NEWTON:-1}
REF_TOL=${REF_TOL:-1e-8}

[[ -x $BENCH_TWIST ]] || { echo "no bench_twist at $BENCH_TWIST (build target bench_twist)" >&2; exit 2; }
[[ -f $MESH ]] || { echo "missing mesh $MESH" >&2; exit 2; }
command -v python3 >/dev/null || { echo "python3 is needed for the summary" >&2; exit 2; }
mkdir -p "$RESULTS_DIR/curves"
RAW=$RESULTS_DIR/raw.jsonl
REF=$RESULTS_DIR/reference.jsonl
: >"$RAW"
: >"$REF"
COMMON=(--mesh "$MESH" --E "$E")
[[ -n $STEPS ]] && COMMON+=(--steps "$STEPS")
[[ -n $RAMP_STEPS ]] && COMMON+=(--ramp-steps "$RAMP_STEPS")

{
  echo "date: $(date -Is)"
  echo "command: $0 $*"
  echo "nproc: $(nproc)"
  echo "cpu: $(lscpu | sed -n 's/^Model name:[[:space:]]*//p' | head -1)"
  echo "kernel: $(uname -sr)"
  echo "load at start: $(cut -d' ' -f1-3 /proc/loadavg)"
  echo "binary: $BENCH_TWIST (built $(date -Is -r "$BENCH_TWIST"))"
  echo "settings: MESH=$MESH E=$E REPS=$REPS STEPS='$STEPS' RAMP_STEPS='$RAMP_STEPS'"
  echo "          BULLET_RELAXED_TOL=$BULLET_RELAXED_TOL BULLET_PC_TOL=$BULLET_PC_TOL BULLET_NEWTON2=$BULLET_NEWTON2 OURS_ONE_NEWTON=$OURS_ONE_NEWTON REF_TOL=$REF_TOL"
} >"$RESULTS_DIR/machine.txt"

# Configurations: "name|key|bench_twist arguments" (key: file-name-safe).
CONFIGS=(
  "ours neo-Hookean CG 1e-4|ours_nh|--solver torsion-cg --law neo_hookean --tolerance 1e-4 --threads 1"
  "ours corotated CG 1e-4|ours_corot|--solver torsion-cg --law corotated --tolerance 1e-4 --threads 1"
  "Bullet neo-Hookean default|bullet_nh_default|--solver bullet-implicit --law neo_hookean"
  "Bullet neo-Hookean tol=$BULLET_RELAXED_TOL|bullet_nh_relaxed|--solver bullet-implicit --law neo_hookean --tolerance $BULLET_RELAXED_TOL"
  "Bullet neo-Hookean mass-pc tol=$BULLET_PC_TOL|bullet_nh_masspc|--solver bullet-implicit --law neo_hookean --tolerance $BULLET_PC_TOL --mass-preconditioner"
)
if [[ $BULLET_NEWTON2 == 1 ]]; then
  CONFIGS+=("Bullet neo-Hookean newton=2 tol=$BULLET_RELAXED_TOL|bullet_nh_newton2|--solver bullet-implicit --law neo_hookean --tolerance $BULLET_RELAXED_TOL --newton 2")
fi
if [[ $OURS_ONE_NEWTON == 1 ]]; then
  CONFIGS+=("ours neo-Hookean CG 1e-4 newton-tol 1e-4|ours_nh_newton1e-4|--solver torsion-cg --law neo_hookean --tolerance 1e-4 --newton-tolerance 1e-4 --threads 1")
  CONFIGS+=("ours neo-Hookean CG 1e-4 newton-tol 1e-3|ours_nh_newton1e-3|--solver torsion-cg --law neo_hookean --tolerance 1e-4 --newton-tolerance 1e-3 --threads 1")
fi

annotate() {  # line config key rep -> JSON line with them added
  python3 -c 'import json,sys; j=json.loads(sys.argv[1]); j.update(config=sys.argv[2], key=sys.argv[3], rep=int(sys.argv[4])); print(json.dumps(j))' "$@"
}
brief() {
  python3 -c 'import json,sys; j=json.loads(sys.argv[1]); print(j.get("status"), "%.1f steps/s" % (j.get("steps_per_s") or 0), "newton", j.get("newton_mean"), "cg/step %.1f" % (j.get("iterations_mean") or 0), "torque", j.get("end_torque"))' "$1"
}

# Accuracy references, once: our law solved tightly (CG and Newton at REF_TOL: a Newton direction
# is solved only as far as the Newton tolerance needs).
echo "reference: ours neo-Hookean CG $REF_TOL" >&2
line=$(OMP_NUM_THREADS=1 "$BENCH_TWIST" --solver torsion-cg --law neo_hookean --tolerance "$REF_TOL" --newton-tolerance "$REF_TOL" --threads 1 "${COMMON[@]}" \
         --label reference --curve "$RESULTS_DIR/curves/reference_ours_nh.csv" \
         --dump-positions "$RESULTS_DIR/curves/reference_ours_nh.pos") || line='{"status":"crashed"}'
annotate "$line" "reference ours neo-Hookean CG $REF_TOL" reference_ours_nh 0 >>"$REF"
echo "reference: $(brief "$line")" >&2

n=${#CONFIGS[@]}
for ((rep = 1; rep <= REPS; rep++)); do
  # The order rotates from one repetition to the next (no configuration always first).
  for ((k = 0; k < n; k++)); do
    IFS='|' read -r name key args <<<"${CONFIGS[$(((k + rep - 1) % n))]}"
    # shellcheck disable=SC2086
    line=$(OMP_NUM_THREADS=1 "$BENCH_TWIST" $args "${COMMON[@]}" --label "$name" \
             --curve "$RESULTS_DIR/curves/${key}_rep$rep.csv" \
             --dump-positions "$RESULTS_DIR/curves/${key}_rep$rep.pos") || line='{"status":"crashed"}'
    annotate "$line" "$name" "$key" "$rep" >>"$RAW"
    echo "rep $rep [$((k + 1))/$n] $name: $(brief "$line")" >&2
  done
done
echo "load at end: $(cut -d' ' -f1-3 /proc/loadavg)" >>"$RESULTS_DIR/machine.txt"

python3 "$ROOT/tests/bench/summarize_hyperelastic_twist.py" "$RESULTS_DIR" "$MESH"
