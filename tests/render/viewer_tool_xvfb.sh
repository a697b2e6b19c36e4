#!/usr/bin/env bash
# `torsion view` moving a tool with a manual device (--device NAME=manual), under a virtual X
# server. The exit report gives each tool's device goal, body pose and (the manual tool's)
# rendered force; G and U log the grasper's jaw gap when pressed.
#  1. palpation, probe=manual: RIGHT x3, UP, PAGEUP, Shift+PAGEUP move the device's goal by
#     exactly those key steps (0.05 of the scene's size each, 5 degrees) and the probe follows:
#     its coupling (k = 500 N/m on 0.02 kg, critically damped: 1/omega = 6 ms, under one 10 ms
#     step) has settled within a few of the ~50 steps after the last key, so the body sits on
#     the goal but for its weight's static sag m g / k = 0.39 mm along -z.
#  2. palpation, probe=manual: a Ctrl + left drag moves the goal in the screen plane and the
#     probe follows it.
#  3. grasp_lift, grasper=manual: G closes the jaws at 2 x closing_speed (0.2 m/s), U opens
#     them again.
#  4. tool_and_hand, probe=manual: RIGHT moves the tool; M takes the hand and M again gives the
#     keys back to the tool, whose goal the next RIGHT moves; M takes the hand once more and the
#     last RIGHT moves the hand: two key steps for the tool, one for the hand.
#  5. tool_and_hand: a hand given up with M stays where the keys left it.
#  6. palpation: the probe pressed into the organ, the device renders the organ's push.
#  7. a manual device on a hand is refused.
# Skipped (77) without xvfb-run.
# Usage: viewer_tool_xvfb.sh TORSION SCENES_DIR
set -u
torsion=$1 scenes=$2
command -v xvfb-run >/dev/null || { echo "xvfb-run not found (Debian: xvfb): skipped"; exit 77; }
fail() { echo "FAIL: $*"; exit 1; }
keys=$(mktemp)
trap 'rm -f "$keys"' EXIT
# view SCENE FRAMES KEYS [OPTIONS...]: the viewer's output; its exit code must be 0.
view() {
  local scene=$1 frames=$2
  printf "$3" > "$keys"
  shift 3
  out=$(timeout 120 xvfb-run -a -s "-screen 0 640x480x24" "$torsion" view "$scenes/$scene" \
        --size 320x240 --steps-per-frame 1 --frames "$frames" --script "$keys" "$@" 2>&1)
  local rc=$?
  echo "$out"
  [ $rc -eq 0 ] || fail "$scene: exit code $rc"
  echo "$out" | grep -qE "^viewer: $frames frames, $frames steps, .*, stable$" ||
    fail "$scene: unexpected summary"
}

# The probe's exit line as 15 numbers: goal position, goal turn, body position, body turn (each a
# rotation vector) and the force its device renders; FAIL on any other line.
probe_numbers() {
  python3 - "$(echo "$out" | grep -E "^viewer: tool 'probe' ")" <<'PY'
import re, sys
num = r'([0-9.e+-]+)'
vec = rf'\({num}, {num}, {num}\)'
m = re.fullmatch(rf"viewer: tool 'probe' \(manual\): goal at {vec} m turned {vec} rad, "
                 rf"body at {vec} m turned {vec} rad, renders {vec} N", sys.argv[1])
if m is None:
    print(f"FAIL: unexpected tool line: {sys.argv[1]!r}", file=sys.stderr); sys.exit(1)
print(" ".join(m.groups()))
PY
}

# 1. Keys.
view palpation.json 60 '5 key RIGHT\n6 key RIGHT\n7 key RIGHT\n8 key UP\n9 key PAGEUP\n10 key PAGEUP shift\n' \
  --device probe=manual
echo "$out" | grep -qx "tool 'probe': device manual, lockstep haptic loop at 1000 Hz" ||
  fail "the viewer did not say the probe's device is manual"
numbers=$(probe_numbers) || exit 1
python3 - "$numbers" "$scenes" <<'PY' || exit 1
import math, sys
v, scenes = [float(x) for x in sys.argv[1].split()], sys.argv[2]
def check(ok, what):
    if not ok:
        print("FAIL:", what); sys.exit(1)
goal, goal_turn, body, body_turn = v[0:3], v[3:6], v[6:9], v[9:12]
start = (-0.03, 0, 0.045)  # palpation.json's probe pose
moved = [g - s for g, s in zip(goal, start)]
# One key step is 0.05 of the diagonal of the FEM bodies' bounding box; the organ's rest box
# (organ_1728.node), which its settling under gravity changes by well under 1 %.
nodes = [list(map(float, l.split()[1:4])) for l in
         open(f"{scenes}/../../assets/meshes/organ_1728.node").read().splitlines()[1:]
         if l.strip() and not l.startswith('#')]
diag = math.dist([min(c) for c in zip(*nodes)], [max(c) for c in zip(*nodes)])
step = moved[1]
check(abs(step - 0.05 * diag) <= 0.01 * 0.05 * diag,
      f"one key step moved the goal {step} m, expected 0.05 x {diag:.4g} m")
# Each press takes the box as it is then: the settling organ changes it by ~1e-4 between them
# (the report prints 6 digits: angles to 1e-6).
check(abs(moved[0] - 3 * step) < 1e-3 * step and abs(moved[2] - step) < 1e-3 * step,
      f"goal moved {moved}: expected 3, 1 and 1 key steps of {step} m along x, y, z")
check(abs(goal_turn[2] - math.radians(5)) < 1e-6 and abs(goal_turn[0]) < 1e-9
      and abs(goal_turn[1]) < 1e-9, f"goal turned {goal_turn}, expected 5 degrees about z")
sag = 0.02 * 9.81 / 500  # m g / k
lag = [b - g for b, g in zip(body, goal)]
check(abs(lag[0]) < 5e-5 and abs(lag[1]) < 5e-5,
      f"the probe is {lag} m off its goal: it did not follow along x, y")
check(abs(-lag[2] - sag) < 0.05 * sag, f"the probe hangs {-lag[2]} m below its goal, "
      f"expected its weight's sag m g / k = {sag:.4g} m")
check(all(abs(b - g) < 1e-3 for b, g in zip(body_turn, goal_turn)),
      f"the probe turned {body_turn}, its goal {goal_turn}")
print(f"PASS: keys moved the probe's goal {moved} m (key step {step:.5g} m) and turned it "
      f"{goal_turn[2]:.5g} rad; the probe followed to within {max(map(abs, lag[:2])):.2g} m, "
      f"hanging {-lag[2]:.4g} m below it")
PY

# 2. Ctrl + left drag.
view palpation.json 40 '5 drag left 30 -20 ctrl\n' --device probe=manual
numbers=$(probe_numbers) || exit 1
python3 - "$numbers" <<'PY' || exit 1
import sys
v = [float(x) for x in sys.argv[1].split()]
goal, body = v[0:3], v[6:9]
moved = sum((g - s) ** 2 for g, s in zip(goal, (-0.03, 0, 0.045))) ** 0.5
lag = [b - g for b, g in zip(body, goal)]
if moved < 1e-3:
    print(f"FAIL: a 36-pixel drag moved the goal only {moved} m"); sys.exit(1)
if abs(lag[0]) > 5e-5 or abs(lag[1]) > 5e-5 or abs(-lag[2] - 0.02 * 9.81 / 500) > 2e-5:
    print(f"FAIL: the probe is {lag} m off its goal after the drag"); sys.exit(1)
print(f"PASS: Ctrl + drag moved the probe's goal {moved:.4g} m; the probe followed")
PY

# 3. G and U on a grasper.
view grasp_lift.json 75 '5 key G\n35 key U\n' --device grasper=manual
python3 - "$out" <<'PY' || exit 1
import re, sys
out = sys.argv[1]
def check(ok, what):
    if not ok:
        print("FAIL:", what); sys.exit(1)
num = r'([0-9.e+-]+)'
held = re.search(rf"^viewer: tool 'grasper': button 1 held at step \d+, t = {num} s; "
                 rf"jaws {num} m apart$", out, re.M)
let_go = re.search(rf"^viewer: tool 'grasper': button 1 let go at step \d+, t = {num} s; "
                   rf"jaws {num} m apart$", out, re.M)
end = re.search(rf"^viewer: tool 'grasper' \(manual\): .*, jaws {num} m apart, renders .*$", out, re.M)
check(held and let_go and end, "missing G, U or exit lines")
t_g, gap_g = float(held[1]), float(held[2])
t_u, gap_u = float(let_go[1]), float(let_go[2])
gap_end = float(end[1])
opening, speed, dt = 0.3, 0.1, 0.01  # grasp_lift.json
check(abs(gap_g - opening) < 1e-3, f"jaws {gap_g} m apart before G, expected {opening} open")
# Each jaw closes at closing_speed from the first step after G to the step of U.
expected = opening - 2 * speed * (t_u - t_g)
check(abs(gap_u - expected) <= 2 * speed * dt,
      f"jaws {gap_u} m apart at U, {t_u - t_g:g} s after G: expected {expected:.4g} "
      f"(closing at 2 x {speed} m/s)")
check(gap_end > gap_u + 0.05 and gap_end <= opening + 1e-3,
      f"jaws {gap_end} m apart at exit, {gap_u} m at U: U did not open them")
print(f"PASS: G closed the jaws {gap_g:.4g} -> {gap_u:.4g} m in {t_u - t_g:g} s, "
      f"U opened them to {gap_end:.4g} m")
PY

# 4. M takes the hand from the tool and gives it back.
view tool_and_hand.json 30 '5 key RIGHT\n8 key M\n9 key M\n10 key RIGHT\n12 key M\n13 key RIGHT\n' \
  --device probe=manual
python3 - "$out" <<'PY' || exit 1
import re, sys
out = sys.argv[1]
def check(ok, what):
    if not ok:
        print("FAIL:", what); sys.exit(1)
num = r'([0-9.e+-]+)'
vec = rf'\({num}, {num}, {num}\)'
tool = re.search(rf"^viewer: tool 'probe' \(manual\): goal at {vec} m", out, re.M)
hand = re.search(rf"^viewer: hand 'hand' \([a-z]+\): goal at {vec} m", out, re.M)
check(tool and hand, "missing tool or hand line")
tool_moved = [float(x) - s for x, s in zip(tool.groups(), (0.25, 0, 0.6))]
hand_moved = [float(x) - s for x, s in zip(hand.groups(), (0, 0, 1.15))]
# The hand turns about its own origin: only the key moves that.
check(hand_moved[0] > 0.01 and abs(hand_moved[1]) < 1e-9 and abs(hand_moved[2]) < 1e-9,
      f"the hand's goal moved {hand_moved}: one key step along x expected (M took it)")
check(abs(tool_moved[0] - 2 * hand_moved[0]) < 0.02 * hand_moved[0]
      and abs(tool_moved[1]) < 1e-9 and abs(tool_moved[2]) < 1e-9,
      f"the tool's goal moved {tool_moved}: two key steps along x expected (before M and "
      f"after M again), the hand's one was {hand_moved[0]}")
print(f"PASS: the keys moved the tool {tool_moved[0]:.4g} m and, after M, the hand "
      f"{hand_moved[0]:.4g} m")
PY

# 5. A hand left with M stays where the keys left it: its script no longer moves it (it would
#    jump back to the script's frame, at x = 0).
view tool_and_hand.json 30 '5 key M\n6 key RIGHT\n8 key M\n' --device probe=manual
python3 - "$out" <<'PY' || exit 1
import re, sys
out = sys.argv[1]
num = r'([0-9.e+-]+)'
hand = re.search(rf"^viewer: hand 'hand' \([a-z]+\): goal at \({num}, {num}, {num}\) m", out, re.M)
if not hand:
    print("FAIL: missing hand line"); sys.exit(1)
x = float(hand.group(1))
if not x > 0.01:
    print(f"FAIL: the hand's goal is at x = {x} at exit, 22 steps after M gave it up: it went "
          f"back to its script (x = 0) instead of staying one key step along x")
    sys.exit(1)
print(f"PASS: the hand left with M stayed at x = {x:.4g} m")
PY

# 6. Pressed into the organ (PageDown twice: 15 mm below its start, 6 mm below the surface),
#    the probe is held up by the organ and the device renders that push: the coupling's pull
#    k (z_body - z_goal) plus the weight it carries, m g = 0.196 N, upward, within 10 % (the
#    device glides to each key's pose over 0.1 s, so the loop's passivity controller has no
#    jump to take back and renders the whole force).
view palpation.json 60 '5 key PAGEDOWN\n6 key PAGEDOWN\n' --device probe=manual
numbers=$(probe_numbers) || exit 1
python3 - "$numbers" <<'PY' || exit 1
import sys
v = [float(x) for x in sys.argv[1].split()]
goal_z, body_z, fz = v[2], v[8], v[14]
expected = 500 * (body_z - goal_z) + 0.02 * 9.81
if not (body_z - goal_z > 1e-3 and abs(fz - expected) <= 0.1 * expected):
    print(f"FAIL: the probe is {body_z - goal_z:.4g} m above its goal and the device renders "
          f"fz = {fz:.4g} N; expected {expected:.4g} N (k dz + m g) within 10 %")
    sys.exit(1)
print(f"PASS: pressed into the organ, the device renders {fz:.4g} N (k dz + m g = {expected:.4g})")
PY

# 7. Manual devices move tools only.
printf '' > "$keys"
out=$(timeout 60 xvfb-run -a -s "-screen 0 640x480x24" "$torsion" view \
      "$scenes/tool_and_hand.json" --frames 2 --device hand=manual 2>&1)
rc=$?
echo "$out"
[ $rc -eq 1 ] || fail "hand=manual: exit code $rc, expected 1"
echo "$out" | grep -qx "error: --device 'hand=manual': manual moves a tool (a dynamic rigid body); torsion view's M key takes hand 'hand'" ||
  fail "hand=manual: unexpected message"
echo "PASS: a manual device on a hand refused"
