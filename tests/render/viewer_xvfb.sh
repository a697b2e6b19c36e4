#!/usr/bin/env bash
# The viewer under a virtual X server: open a scene, feed it synthetic input for a few frames,
# close cleanly, and leave a non-empty screenshot. Skipped (77) without xvfb-run.
# Usage: viewer_xvfb.sh TORSION SCENE SCRIPT SCREENSHOT
set -u
torsion=$1 scene=$2 script=$3 shot=$4
command -v xvfb-run >/dev/null || { echo "xvfb-run not found (Debian: xvfb): skipped"; exit 77; }
rm -f "$shot"
out=$(timeout 120 xvfb-run -a -s "-screen 0 1024x768x24" \
      "$torsion" view "$scene" --frames 30 --script "$script" --screenshot "$shot" --size 640x480 2>&1)
rc=$?
echo "$out"
[ $rc -eq 0 ] || { echo "FAIL: exit code $rc"; exit 1; }
echo "$out" | grep -Eq '^viewer: 30 frames, [0-9]+ steps, hand manual, [1-9][0-9]* nodes grabbed, stable$' ||
  { echo "FAIL: unexpected summary"; exit 1; }
size=$(stat -c %s "$shot" 2>/dev/null || echo 0)
[ "$size" -gt 10000 ] || { echo "FAIL: screenshot $shot missing or blank ($size bytes)"; exit 1; }
echo "PASS: screenshot $shot ($size bytes)"
