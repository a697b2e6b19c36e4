#!/usr/bin/env bash
# Regenerates every mesh in assets/meshes/ with the built `torsion` tool and Debian's tools.
#
#   assets/recipes/make_assets.sh            # uses build/demos/torsion
#   TORSION=/path/to/torsion assets/recipes/make_assets.sh
#
# Needs the Debian packages tetgen (the mesher, run as a program), libcgal-demo (the dragon's
# source surface), and libcgal-dev + g++ (to compile dragon_surface.cpp, a recipe-only helper).
# When run as root, missing packages are installed with apt-get; otherwise it says what to install.
# Every step is deterministic: rerunning with the same package versions gives identical files.
# Finally it prints `torsion mesh info` of every asset (the numbers in assets/README.md).
set -euo pipefail

here=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
assets=$(dirname "$here")
repo=$(dirname "$assets")
meshes="$assets/meshes"
torsion=${TORSION:-$repo/build/demos/torsion}

if [[ ! -x "$torsion" ]]; then
  echo "make_assets.sh: no torsion tool at $torsion; build it first" >&2
  echo "  (cmake -S $repo -B $repo/build -G Ninja && cmake --build $repo/build), or set TORSION" >&2
  exit 1
fi

need_packages() {
  local missing=()
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  ((${#missing[@]} == 0)) && return 0
  if [[ $(id -u) -eq 0 ]]; then
    echo "== installing ${missing[*]}"
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq "${missing[@]}" >/dev/null
  else
    echo "make_assets.sh: please install: apt-get install ${missing[*]}" >&2
    exit 1
  fi
}

need_packages tetgen libcgal-dev libcgal-demo g++ libgmp-dev libmpfr-dev
echo "== tool versions"
dpkg-query -W -f='  ${Package} ${Version}\n' tetgen libcgal-dev libcgal-demo g++
mkdir -p "$meshes"

# ---- Cylinders: radius 1, length 10, along +z from z = 0 ----
for n in 2430 4323 8332 31558; do
  echo "== cylinder_$n"
  "$torsion" mesh cylinder --radius 1 --length 10 --tets "$n" -o "$meshes/cylinder_$n.node"
done

# ---- Dragon (a seated guardian lion, CGAL's ChineseDragon-10kv.off), about 4300 tets ----
echo "== dragon_4300"
work=$(mktemp -d "${TMPDIR:-/tmp}/torsion-assets-XXXXXX")
trap 'rm -rf "$work"' EXIT
data=""
for d in /usr/share/doc/libcgal-demo /usr/share/doc/libcgal-dev; do
  [[ -f "$d/data.tar.gz" ]] && data="$d/data.tar.gz" && break
done
if [[ -z "$data" ]]; then
  echo "make_assets.sh: CGAL's data.tar.gz not found (Debian package libcgal-demo)" >&2
  exit 1
fi
tar -xzf "$data" -C "$work" data/meshes/ChineseDragon-10kv.off
echo "  compiling dragon_surface.cpp (CGAL; takes about a minute)"
g++ -O2 -std=c++17 -o "$work/dragon_surface" "$here/dragon_surface.cpp" -lgmp -lmpfr
# alpha = diag/35, offset = diag/1050, edge length = diag/24.8, scale 0.1, tilt 72.5 deg,
# 5 remeshing iterations: 965 vertices, 1926 triangles.
"$work/dragon_surface" "$work/data/meshes/ChineseDragon-10kv.off" "$work/dragon_surface.off" \
  35 1050 24.8 0.1 72.5 5
# Second opinion on self-intersections: tetgen -d.
if (cd "$work" && tetgen -d dragon_surface.off 2>&1) | grep -q "intersects"; then
  echo "make_assets.sh: tetgen -d finds self-intersections in the dragon surface" >&2
  exit 1
fi
"$torsion" mesh tetrahedralize "$work/dragon_surface.off" -o "$meshes/dragon_4300.node" \
  --keep-surface --min-dihedral 10 --max-volume 0

# ---- Contact scenes: a small rod (tetgen), structured boxes and a ball (no tetgen) ----
echo "== rod_1200, rod_slender_7951, slab_768, block_162, paddle_108, ball_384"
"$torsion" mesh cylinder --radius 0.15 --length 1.2 --tets 1200 -o "$meshes/rod_1200.node"
# The plectoneme's slender rod (demos/scenes/plectoneme.json): 40 radii long.
"$torsion" mesh cylinder --radius 0.01 --length 0.4 --tets 7951 -o "$meshes/rod_slender_7951.node"
"$torsion" mesh box --min -0.5 -0.5 0 --max 0.5 0.5 0.2 --cells 8 8 2 -o "$meshes/slab_768.node"
"$torsion" mesh box --min -0.1 -0.1 0 --max 0.1 0.1 0.2 --cells 3 3 3 -o "$meshes/block_162.node"
"$torsion" mesh box --min -0.3 -0.04 0 --max 0.3 0.04 0.3 --cells 6 1 3 \
  -o "$meshes/paddle_108.node"
"$torsion" mesh ball --radius 0.25 --cells 4 -o "$meshes/ball_384.node"

# ---- Tool scenes (demos/scenes/palpation.json, tool_and_hand.json): a soft organ-sized block ----
echo "== organ_1728"
"$torsion" mesh box --min -0.06 -0.04 0 --max 0.06 0.04 0.03 --cells 12 8 3 \
  -o "$meshes/organ_1728.node"

# ---- Bullet's deformable demos re-created (demos/scenes/bullet_*.json): soft cube, sheet ----
echo "== cube_384, sheet_1536"
"$torsion" mesh box --min -2 -2 -2 --max 2 2 2 --cells 4 4 4 -o "$meshes/cube_384.node"
"$torsion" mesh box --min -4 -4 -0.1 --max 4 4 0.1 --cells 16 16 1 -o "$meshes/sheet_1536.node"

echo "== torsion mesh info"
for f in "$meshes"/cylinder_2430.node "$meshes"/cylinder_4323.node "$meshes"/cylinder_8332.node \
  "$meshes"/cylinder_31558.node "$meshes"/dragon_4300.node "$meshes"/rod_1200.node "$meshes"/rod_slender_7951.node \
  "$meshes"/slab_768.node "$meshes"/block_162.node "$meshes"/paddle_108.node \
  "$meshes"/ball_384.node "$meshes"/organ_1728.node "$meshes"/cube_384.node \
  "$meshes"/sheet_1536.node; do
  (cd "$meshes" && "$torsion" mesh info "$(basename "$f")")
  echo
done
