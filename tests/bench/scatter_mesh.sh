#!/usr/bin/env bash
# Writes a copy of a TetGen mesh (.node/.ele) with its nodes scattered as a mesher's insertion
# order leaves them: node i becomes i * K mod n (K prime, not dividing n). The body is the same;
# only the numbering differs. Used to time a mesh "from elsewhere" (docs/performance.md, "Node
# order").
#   tests/bench/scatter_mesh.sh assets/meshes/cylinder_8332.node /tmp/s8332.node [K=1031]
set -euo pipefail
in=${1:?input .node}
out=${2:?output .node}
k=${3:-1031}
n=$(awk 'NR == 1 { print $1; exit }' "$in")
{ head -n 1 "$in"
  awk -v k="$k" -v n="$n" 'NR > 1 && NF >= 4 && $1 ~ /^[0-9]+$/ { $1 = ($1 * k) % n; print }' "$in" |
    sort -n -k1,1; } >"$out"
awk -v k="$k" -v n="$n" 'NR == 1 { print; next } NF >= 5 && $1 ~ /^[0-9]+$/ {
       for (i = 2; i <= 5; ++i) $i = ($i * k) % n } { print }' "${in%.node}.ele" >"${out%.node}.ele"
