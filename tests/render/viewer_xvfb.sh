#!/usr/bin/env bash
# The viewer under a virtual X server: open a scene, feed it synthetic input for a few frames,
# close cleanly, and leave a non-empty screenshot. The script's live edits (E x1.5, then dt x2)
# must reach the running world without a restart: the exit summary reads E and dt back from the
# world, the world's step count equals the viewer's (a restart would reset it), and the time
# after the dt edit grows by the new dt per step. Skipped (77) without xvfb-run.
# Usage: viewer_xvfb.sh TORSION SCENE SCRIPT SCREENSHOT
set -u
torsion=$1 scene=$2 script=$3 shot=$4
command -v xvfb-run >/dev/null || { echo "xvfb-run not found (Debian: xvfb): skipped"; exit 77; }
rm -f "$shot"
out=$(timeout 120 xvfb-run -a -s "-screen 0 1024x768x24" \
      "$torsion" view "$scene" --frames 30 --steps-per-frame 1 --script "$script" \
      --screenshot "$shot" --size 640x480 2>&1)
rc=$?
echo "$out"
fail() { echo "FAIL: $*"; exit 1; }
[ $rc -eq 0 ] || fail "exit code $rc"
summary=$(echo "$out" | grep -E '^viewer: 30 frames, [0-9]+ steps, hand manual, [1-9][0-9]* nodes grabbed, stable$') ||
  fail "unexpected summary"
viewer_steps=$(echo "$summary" | sed -E 's/^viewer: 30 frames, ([0-9]+) steps.*/\1/')
# "viewer: world at step N, t = T s; DT 0.02 S  E 150000 PA ..." (the scene has dt 0.01, E 1e5)
world=$(echo "$out" | grep -E '^viewer: world at step ' | tail -1)
[ -n "$world" ] || fail "no world line at exit"
edits=$(echo "$out" | grep -c '^viewer: live edit, world at step ')
[ "$edits" -eq 2 ] || fail "expected 2 live edits in the log, found $edits"
python3 - "$world" "$viewer_steps" "$(echo "$out" | grep '^viewer: live edit' | tail -1)" <<'PY' || exit 1
import re, sys
world, viewer_steps, last_edit = sys.argv[1], int(sys.argv[2]), sys.argv[3]
pat = r'world at step (\d+), t = ([0-9.e+-]+) s; DT ([0-9.e+-]+) S  E ([0-9.e+-]+) PA'
w, e = re.search(pat, world), re.search(pat, last_edit)
steps, t, dt, young = int(w[1]), float(w[2]), float(w[3]), float(w[4])
edit_steps, edit_t = int(e[1]), float(e[2])
def check(ok, what):
    if not ok:
        print("FAIL:", what); sys.exit(1)
check(abs(young - 1.5e5) < 1, f"E at exit {young} Pa, expected 1.5e5 (1e5 x 1.5, live)")
check(abs(dt - 0.02) < 1e-12, f"dt at exit {dt} s, expected 0.02 (0.01 x 2, live)")
check(steps == viewer_steps, f"world step {steps} != viewer steps {viewer_steps}: restarted?")
check(edit_steps > 0 and edit_t > 0, "the dt edit happened at t = 0: restarted?")
check(steps > edit_steps, "no step after the dt edit")
expected = edit_t + (steps - edit_steps) * 0.02  # every step after the edit is 0.02 s long
check(abs(t - expected) < 1e-9, f"t = {t} s at exit, expected {expected} from the new dt")
print(f"PASS: live edits: E {young:g} Pa, dt {dt:g} s, {steps} steps without restart, t = {t:g} s")
PY
size=$(stat -c %s "$shot" 2>/dev/null || echo 0)
[ "$size" -gt 10000 ] || fail "screenshot $shot missing or blank ($size bytes)"
echo "PASS: screenshot $shot ($size bytes)"
