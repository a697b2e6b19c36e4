#!/usr/bin/env bash
# Regenerates the picture of every scene for docs/rendering.md, one command:
#   bash docs/figures/make_scene_figures.sh [BUILD_DIR] [SCENE ...]
# For each demos/scenes/*.json (or only the named scenes), runs it headless with
# `torsion run --render` (OSMesa, 800x600, first and last frame only) and writes
# docs/figures/scene_<name>.png: the first and the last frame side by side (before | after, with
# Debian's ffmpeg; without it, the last frame alone). A scene runs its own `steps`, except those
# listed in STEPS below, whose full run is long (the big cylinders): their picture is taken
# earlier. The camera is the
# renderer's default fitted to the scene, or the scene's own `camera` entry (docs/scene-format.md).
# Look at every picture before committing it.
set -euo pipefail
cd "$(dirname "$0")/../.."
build=${1:-build}
shift || true
torsion=$build/demos/torsion
[ -x "$torsion" ] || { echo "no $torsion: build first (cmake --build $build --target torsion)"; exit 1; }

declare -A STEPS=(
  [twist_cylinder_4323]=1600   # 1.6 rad of the 2 pi turn
  [twist_cylinder_8332]=1600
  [twist_cylinder_31558]=800   # 0.8 rad; ~1 min on 2 cores
  [press]=100                  # the plate down 6 cm and holding (it lifts at 1.1 s)
  [haptic_cylinder]=700        # device at 70 s of Figure 6.7 (speed 10): turned 0.5 rad about z
  [haptic_dragon]=350          # neck turned 90 degrees and held; button 2 releases it at 4 s
  [soft_grasp]=150             # the block lifted 0.3 m between the fingers
  [palpation]=300              # the probe halfway along its slide over the organ
  [tool_and_hand]=350          # the probe pressed into the twisting bar
  [grasp_lift]=350             # the block lifted 0.2 m between the jaws
)

scenes=("$@")
if [ ${#scenes[@]} -eq 0 ]; then
  for f in demos/scenes/*.json; do scenes+=("$(basename "$f" .json)"); done
fi
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
for name in "${scenes[@]}"; do
  scene=demos/scenes/$name.json
  [ -f "$scene" ] || { echo "no scene $scene"; exit 1; }
  steps=()
  [ -n "${STEPS[$name]:-}" ] && steps=(--steps "${STEPS[$name]}")
  echo "== $name ${steps[*]}"
  rm -rf "$work/$name"
  if ! "$torsion" run "$scene" --out "$work/$name" "${steps[@]}" --render "$work/$name/pictures" \
      --render-size 800x600 --render-every 1000000 >"$work/$name.log" 2>&1; then
    cat "$work/$name.log"
    echo "torsion run $scene failed"
    exit 1
  fi
  grep -E '^(done|pictures):' "$work/$name.log" | sed 's/^/   /'
  first=$(ls "$work/$name/pictures"/frame_*.png | sort | head -1)
  last=$(ls "$work/$name/pictures"/frame_*.png | sort | tail -1)
  [ -n "$last" ] || { echo "no picture for $name"; exit 1; }
  if command -v ffmpeg >/dev/null; then
    ffmpeg -v error -y -i "$first" -i "$last" -filter_complex hstack "docs/figures/scene_$name.png"
  else
    echo "   (no ffmpeg: the last frame alone)"
    cp "$last" "docs/figures/scene_$name.png"
  fi
  echo "   -> docs/figures/scene_$name.png"
done
