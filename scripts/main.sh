#!/usr/bin/env bash
# The main job, from a fresh machine: set-up, Release build, then the headless job.
# Until the FEM solver lands, the job inspects every shipped mesh asset and writes a report.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)

bash scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release
cmake --build build -j"$jobs" --target torsion

out=results/assets
mkdir -p "$out"
for node in assets/meshes/*.node; do
  name=$(basename "$node" .node)
  echo "== $name"
  build/demos/torsion mesh info "$node" | tee "$out/$name.txt"
  build/demos/torsion mesh convert "$node" "$out/$name.vtk"
done
echo "Results: $out/ (one .txt report and one ParaView .vtk per mesh)"
