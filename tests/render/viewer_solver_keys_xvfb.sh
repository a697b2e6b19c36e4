#!/usr/bin/env bash
# The viewer's C key steps through every linear solver live (CG with each preconditioner, then
# CHOLMOD, then round again; Shift+C steps back), and the twist keeps running stable through each
# switch, the lagged factorisations included. Skipped (77) without xvfb-run.
# Usage: viewer_solver_keys_xvfb.sh TORSION SCENE
set -u
torsion=$1 scene=$2
command -v xvfb-run >/dev/null || { echo "xvfb-run not found (Debian: xvfb): skipped"; exit 77; }
keys=$(mktemp)
trap 'rm -f "$keys"' EXIT
printf '2 key C\n4 key C\n6 key C\n8 key C\n10 key C\n12 key C\n14 key C shift\n' > "$keys"
out=$(timeout 120 xvfb-run -a -s "-screen 0 1024x768x24" \
      "$torsion" view "$scene" --frames 18 --steps-per-frame 1 --script "$keys" --size 320x240 2>&1)
rc=$?
echo "$out"
fail() { echo "FAIL: $*"; exit 1; }
[ $rc -eq 0 ] || fail "exit code $rc"
seen=$(echo "$out" | grep '^viewer: live edit' | sed -E 's/.*BETA [^ ]+ S  //' | paste -sd,)
# The scene starts on CG block-Jacobi.
expected="cg incomplete_cholesky,cg lagged_cholesky,cg two_level,cholmod,cg jacobi,cg block_jacobi,cg jacobi"
[ "$seen" = "$expected" ] || fail "solver sequence '$seen', expected '$expected'"
echo "$out" | grep -qE '^viewer: 18 frames, 18 steps, .*, stable$' || fail "the run did not end stable after 18 steps"
echo "PASS: C cycles $expected; stable"
