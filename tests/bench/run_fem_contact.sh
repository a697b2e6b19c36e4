#!/usr/bin/env bash
# Contact between FEM bodies, side by side (docs/performance-contact.md, "Contact between FEM
# bodies: cost, and Bullet side by side"): timings of bench_fem_contact, then, with --instructions,
# the instruction counts (callgrind: exact, whatever the machine's load) of each run's step and of
# its contact detection.
#
#   tests/bench/run_fem_contact.sh [--instructions [--instruction-steps N]] [SCENE...]
#   (from the repository root, after building bench_fem_contact; N: steps per callgrind run,
#   default 60, the collide scenes' whole run and soft_stack's ball impact, ~1-3 min each)
#
# Bullet runs twice: with the runner's settings (margin 0.01 m, one Bullet step per scene step)
# and with its contact demos' (margin 0.1 m on the 4 m cubes as Collide, 0.025 m on the 0.2 m
# blocks as PinchFriction; four steps of dt / 4 as DeformableContact and PinchFriction). Both
# stand on a box ground, as Bullet's demos do.
set -euo pipefail

bench=build/tests/bench/bench_fem_contact
instructions=0
instruction_steps=60
scenes=()
while [ $# -gt 0 ]; do
  case "$1" in
    --instructions) instructions=1 ;;
    --instruction-steps) instruction_steps=$2; shift ;;
    *) scenes+=("$1") ;;
  esac
  shift
done
if [ ${#scenes[@]} -eq 0 ]; then
  scenes=(bullet_collide_soft bullet_collide_moving soft_stack soft_grasp)
fi

demo_margin() {
  case "$1" in
    bullet_collide_*) echo 0.1 ;;
    *) echo 0.025 ;;
  esac
}

echo "# $(date -u +%FT%TZ) $(git rev-parse --short HEAD) load: $(cut -d' ' -f1-3 /proc/loadavg)"
for scene in "${scenes[@]}"; do
  file=demos/scenes/$scene.json
  "$bench" "$file" --bullet-ground-box
  # Scenes with hands have no Bullet run (the first call says so).
  if ! grep -q '"hands"' "$file"; then
    "$bench" "$file" --only bullet --bullet-ground-box --bullet-margin "$(demo_margin "$scene")" \
      --bullet-substeps 4
  fi
done
echo "# load after: $(cut -d' ' -f1-3 /proc/loadavg)"

[ "$instructions" -eq 1 ] || exit 0
# Inclusive instructions of the named functions, per run (callgrind_annotate's names).
count() {  # out-file function-pattern
  callgrind_annotate --inclusive=yes --threshold=100 "$1" 2>/dev/null |
    awk -v pattern="$2" 'index($0, pattern) { gsub(",", "", $1); sum += $1 } END { printf "%.0f\n", sum }'
}
out=$(mktemp -d)
for scene in "${scenes[@]}"; do
  file=demos/scenes/$scene.json
  for run in torsion torsion_no_fem_contact bullet; do
    valgrind --tool=callgrind --callgrind-out-file="$out/$scene.$run" "$bench" "$file" \
      --only "$run" --bullet-ground-box --steps "$instruction_steps" > "$out/$scene.$run.json" \
      2> "$out/$scene.$run.err" ||
      { echo "# $scene $run: failed: $(tail -n 1 "$out/$scene.$run.err")"; continue; }
    [ -s "$out/$scene.$run.json" ] || continue
    steps=$(/usr/bin/python3 -c "import json,sys; print(json.loads(open(sys.argv[1]).readline()).get('steps', 0))" "$out/$scene.$run.json")
    [ "$steps" -gt 0 ] || continue
    if [ "$run" = bullet ]; then
      step=$(count "$out/$scene.$run" "btDeformableMultiBodyDynamicsWorld::internalSingleStepSimulation(")
      pairs=$(( $(count "$out/$scene.$run" "btDeformableMultiBodyDynamicsWorld::performDeformableCollisionDetection()") +
                $(count "$out/$scene.$run" "btDeformableMultiBodyDynamicsWorld::performGeometricCollisions(") ))
      rigid=$(count "$out/$scene.$run" "btCollisionWorld::performDiscreteCollisionDetection()")
      solve=$(count "$out/$scene.$run" "btDeformableMultiBodyDynamicsWorld::solveConstraints(")
    else
      step=$(count "$out/$scene.$run" "torsion::FemWorld::step()")
      # In the world's step only (the bench's replayed detect is called from runTorsion).
      pairs=$(count "$out/$scene.$run" "torsion::FemContactIslands::plan(")
      rigid=$(count "$out/$scene.$run" "torsion::RigidContactSolver::detect(")
      solve=0
    fi
    echo "{\"scene\": \"$scene\", \"run\": \"$run\", \"steps\": $steps," \
      "\"instructions_per_step\": $(( step / steps ))," \
      "\"detect_body_pairs_per_step\": $(( pairs / steps ))," \
      "\"detect_rigid_per_step\": $(( rigid / steps ))," \
      "\"bullet_solve_per_step\": $(( solve / steps ))}"
  done
done
rm -rf "$out"
