#!/usr/bin/env bash
# The main job, from a fresh machine: set-up, Release build, then the headless twist of the small
# cylinder (the report's section 6.1.2: r = 1, L = 10, one end fixed, a hand near the other end
# turning 2 pi at 0.1 rad/s, dt = 0.01). Prints its progress; writes its results to
# results/twist_cylinder_2430/. The build compiles through ccache (scripts/ccache_env.sh), so a
# second run rebuilds nothing.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
# shellcheck source=scripts/ccache_env.sh
source scripts/ccache_env.sh
# shellcheck source=scripts/stages.sh
source scripts/stages.sh
trap 'rc=$?; report_stages; ccache_report; exit $rc' EXIT

stage "Set-up (scripts/setup.sh)"
bash scripts/setup.sh
stage "Build of the torsion tool (build/, Release)"
# Unity batches (TORSION_UNITY_BUILD) halve a clean build's minutes on 2 cores.
configure build -DCMAKE_BUILD_TYPE=Release -DTORSION_UNITY_BUILD=ON
build build --target torsion

stage "Twist of the 2430-tet cylinder"
scene=demos/scenes/twist_cylinder_2430.json
out=results/twist_cylinder_2430
build/demos/torsion run "$scene" --out "$out" --render "$out/pictures" --render-every 100
echo
echo "Summary ($out/summary.json):"
cat "$out/summary.json"
echo
echo "Results in $out/: summary.json, wrench.csv (force and torque on the hand and the fixed base), energy.csv, cylinder.vtk (open in ParaView)"
echo "Pictures in $out/pictures/: frame_00000.png ... (every 100 steps; an MP4 too when ffmpeg is installed)"
