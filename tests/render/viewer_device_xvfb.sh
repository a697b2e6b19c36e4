#!/usr/bin/env bash
# `torsion view --device`, under a virtual X server (the option and its parsing are the run
# command's, cli/device_options.cpp):
#  1. --device hand=scripted:figure_6_7.json on twist_cylinder_2430 for 60 frames: the viewer
#     says which device drives the hand, exits cleanly with the hand on its device, and the
#     hand followed the device, not the scene's script: the trajectory's first phase turns the
#     device about its x axis at 0.03 rad/s (the scene's script would have turned it about z at
#     0.1 rad/s), so after t seconds the goal is turned (0.03 t, 0, 0) rad and the grabbed patch,
#     which pursues the goal, is on it. The manual-hand keys (M, arrows, G) are fed too: they
#     must leave the device's hand to the device, and say so.
#  2. --device hand=spacemouse with no spacenavd running: exit code 1 (no crash, no window) and
#     a message naming the hand and what is missing (the daemon, or libspnav in this build).
#  3. --device foot=...: the run command's error, naming the hands the scene has.
# Skipped (77) without xvfb-run.
# Usage: viewer_device_xvfb.sh TORSION SCENE TRAJECTORY
set -u
torsion=$1 scene=$2 trajectory=$3
command -v xvfb-run >/dev/null || { echo "xvfb-run not found (Debian: xvfb): skipped"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }
view() {
  timeout 120 xvfb-run -a -s "-screen 0 640x480x24" "$torsion" view "$scene" --size 320x240 \
    --steps-per-frame 1 "$@" 2>&1
}

# 1. A scripted device drives the hand.
keys=$(mktemp)
trap 'rm -f "$keys"' EXIT
printf '10 key M\n11 key LEFT\n12 key PAGEUP shift\n13 key G\n' > "$keys"
out=$(view --frames 60 --device "hand=scripted:$trajectory" --script "$keys")
rc=$?
echo "$out"
[ $rc -eq 0 ] || fail "scripted device: exit code $rc"
echo "$out" | grep -qE "^hand 'hand': device scripted\(.*figure_6_7\.json\), lockstep haptic loop at 1000 Hz$" ||
  fail "the viewer did not say which device drives the hand"
[ "$(echo "$out" | grep -c "^viewer: hand 'hand' follows its device: no manual control$")" -eq 4 ] ||
  fail "M, LEFT, PAGEUP and G should each be refused for the device's hand"
echo "$out" | grep -qE '^viewer: 60 frames, 60 steps, hand device, [1-9][0-9]* nodes grabbed, stable$' ||
  fail "unexpected summary"
python3 - "$(echo "$out" | grep -E '^viewer: world at step ' | tail -1)" \
          "$(echo "$out" | grep -E "^viewer: hand 'hand' " | tail -1)" <<'PY' || exit 1
import re, sys
world, hand = sys.argv[1], sys.argv[2]
def check(ok, what):
    if not ok:
        print("FAIL:", what); sys.exit(1)
w = re.search(r'world at step (\d+), t = ([0-9.e+-]+) s', world)
check(w is not None, f"no world line: {world!r}")
t = float(w[2])
num = r'([0-9.e+-]+)'
vec = rf'\({num}, {num}, {num}\)'
h = re.search(rf"hand 'hand' \(device\): goal at {vec} m turned {vec} rad, patch at {vec} m "
              rf"turned {vec} rad, (\d+) nodes grabbed", hand)
check(h is not None, f"unexpected hand line: {hand!r}")
v = [float(x) for x in h.groups()[:12]]
goal_o, goal_r, patch_o, patch_r = v[0:3], v[3:6], v[6:9], v[9:12]
expected = 0.03 * t
# Lockstep: the loop ticks one step's worth of device time before each step, so the goal may
# be one step (0.01 s) of device motion off the world's clock: 0.03 rad/s * 0.01 s = 3e-4 rad.
check(abs(goal_r[0] - expected) <= 3e-4,
      f"goal turned {goal_r[0]} rad about x at t = {t} s; the device turned {expected}")
check(abs(goal_r[1]) < 1e-9 and abs(goal_r[2]) < 1e-9,
      f"goal turned about y or z {goal_r[1:]}: not the device's motion (the script turns z)")
check(all(abs(a - b) < 1e-9 for a, b in zip(goal_o, (0, 0, 9.9))),
      f"goal moved to {goal_o}: the first phase only rotates")
# The patch pursues the goal under a speed limit far above 0.03 rad/s: it is on it to within
# one step of that motion.
check(all(abs(a - b) <= 3e-4 for a, b in zip(patch_r, goal_r)),
      f"patch turned {patch_r}, goal {goal_r}: the hand does not follow the device")
check(all(abs(a - b) <= 1e-6 for a, b in zip(patch_o, goal_o)), f"patch at {patch_o}")
print(f"PASS: after {t:g} s the device's hand is turned {goal_r[0]:.6g} rad about x "
      f"(expected {expected:.6g}), patch {patch_r[0]:.6g}, {h[13]} nodes grabbed")
PY

# 2. A SpaceMouse with no daemon: a clear refusal, before any window.
if [ -e /var/run/spnav.sock ]; then
  echo "spacenavd runs here: the no-daemon check is skipped"
else
  out=$(view --frames 5 --device hand=spacemouse)
  rc=$?
  echo "$out"
  [ $rc -eq 1 ] || fail "spacemouse without a daemon: exit code $rc, expected 1"
  echo "$out" | grep -qE "^error: .*hands\[0\] 'hand': device: SpaceMouse: (cannot connect to the spacenavd daemon|this build of Torsion has no libspnav)" ||
    fail "spacemouse without a daemon: no clear message"
  echo "$out" | grep -q '^viewer: ' && fail "spacemouse without a daemon: the viewer started anyway"
  echo "PASS: spacemouse without a daemon refused"
fi

# 3. The run command's parsing: a hand the scene does not have.
out=$(view --frames 5 --device foot=spacemouse)
rc=$?
echo "$out"
[ $rc -eq 1 ] || fail "unknown hand: exit code $rc, expected 1"
echo "$out" | grep -qx "error: --device 'foot=spacemouse': the scene has no hand or dynamic rigid body named 'foot' (hands: 'hand')" ||
  fail "unknown hand: unexpected message"
echo "PASS: unknown hand refused"
