#!/usr/bin/env bash
# `torsion mesh tetrahedralize`: its default tet size and its Gmsh mesher. One case per call.
#   mesh_checks.sh CASE TORSION
# Exit 0: pass; 77: skipped (the mesher's command is not on PATH); anything else: fail.
set -uo pipefail

case_name=$1
torsion=$2
work_name=torsion-mesh-test
source "$(dirname "$0")/case_helpers.sh"

need() {
  command -v "$1" >/dev/null 2>&1 || skip "the '$1' command is not on PATH"
}

field() {  # field NAME MESH: one value of `torsion mesh info`
  "$torsion" mesh info "$2" | sed -n "s/^$1 \{1,\}\([^ ]*\).*/\1/p"
}

write_box_off() {  # write_box_off FILE SIZE: a closed cube [0, SIZE]^3, outward triangles
  local s=$2
  cat >"$1" <<END_OF_SURFACE
OFF
8 12 0
0 0 0
$s 0 0
$s $s 0
0 $s 0
0 0 $s
$s 0 $s
$s $s $s
0 $s $s
3 0 2 1
3 0 3 2
3 4 5 6
3 4 6 7
3 0 1 5
3 0 5 4
3 1 2 6
3 1 6 5
3 2 3 7
3 2 7 6
3 3 0 4
3 3 4 7
END_OF_SURFACE
}

case $case_name in
  tetrahedralize_default_size_follows_the_surface)
    # Without --max-volume the tet size comes from the surface's size: a 1 m and a 100 m cube get
    # the same mesh up to scale (tetgen is scale-invariant up to round-off), of a useful size
    # (hundreds to tens of thousands of tets), and --max-volume 0 keeps tetgen's bare minimum.
    need tetgen
    write_box_off small.off 1
    write_box_off large.off 100
    "$torsion" mesh tetrahedralize small.off -o small.node >/dev/null || fail "small cube"
    "$torsion" mesh tetrahedralize large.off -o large.node >/dev/null || fail "large cube"
    "$torsion" mesh tetrahedralize small.off -o bare.node --max-volume 0 >/dev/null || fail "bare"
    a=$(field tets small.node) b=$(field tets large.node) c=$(field tets bare.node)
    echo "tets: 1 m cube $a, 100 m cube $b, no bound $c"
    ((a >= 500 && a <= 50000)) || fail "default size gave $a tets for a cube"
    ((b * 100 >= a * 95 && b * 100 <= a * 105)) || fail "scaled cube: $b tets against $a"
    ((c < a / 10)) || fail "--max-volume 0 should leave tetgen's few tets, got $c"
    [[ $(field volume large.node) == 1e+06 ]] || fail "large cube volume $(field volume large.node)"
    ;;

  tetrahedralize_with_gmsh)
    # --mesher gmsh: a valid mesh of exactly the cube's volume, refined to the default size.
    need gmsh
    write_box_off cube.off 2
    out=$("$torsion" mesh tetrahedralize cube.off -o cube.msh --mesher gmsh) || fail "gmsh run: $out"
    echo "$out"
    grep -Eq "^wrote cube.msh: [0-9]+ tets, .*gmsh, longest edge 0.346" <<<"$out" || fail "report"
    [[ $(field volume cube.msh) == 8 ]] || fail "volume $(field volume cube.msh), expected 8"
    (($(field tets cube.msh) >= 100)) || fail "expected a refined mesh, got $(field tets cube.msh)"
    ;;

  tetrahedralize_ply)
    # The cube [0,2]^3 as PLY in each encoding (binary ones with extra properties and an extra
    # element to skip): each gives a valid mesh of volume exactly 8.
    need tetgen
    /usr/bin/python3 - <<'PY' || fail "writing the PLY files"
import struct
v = [(0, 0, 0), (2, 0, 0), (2, 2, 0), (0, 2, 0), (0, 0, 2), (2, 0, 2), (2, 2, 2), (0, 2, 2)]
quads = [(0, 3, 2, 1), (4, 5, 6, 7), (0, 1, 5, 4), (1, 2, 6, 5), (2, 3, 7, 6), (3, 0, 4, 7)]
head = "ply\nformat %s 1.0\ncomment a cube\nelement vertex 8\nproperty float x\n" \
       "property float y\nproperty float z\nproperty uchar red\n" \
       "element face 6\nproperty list uchar int vertex_indices\n" \
       "element edge 1\nproperty int vertex1\nproperty int vertex2\nend_header\n"
with open("ascii.ply", "w") as f:
    f.write(head % "ascii")
    f.writelines("%g %g %g 7\n" % p for p in v)
    f.writelines("4 %d %d %d %d\n" % q for q in quads)
    f.write("0 1\n")
for name, order in (("little", "<"), ("big", ">")):
    with open(name + ".ply", "wb") as f:
        f.write((head % ("binary_%s_endian" % name)).encode())
        for p in v:
            f.write(struct.pack(order + "fffB", *p, 7))
        for q in quads:
            f.write(struct.pack(order + "Biiii", 4, *q))
        f.write(struct.pack(order + "ii", 0, 1))
PY
    for f in ascii little big; do
      out=$("$torsion" mesh tetrahedralize $f.ply -o $f.node 2>&1) || fail "$f.ply: $out"
      grep -q "from $f.ply: 8 vertices, 12 triangles" <<<"$out" || fail "$f.ply: $out"
      [[ $(field volume $f.node) == 8 ]] || fail "$f.ply: volume $(field volume $f.node)"
    done
    ;;

  *)
    fail "unknown case $case_name"
    ;;
esac
echo "PASS: $case_name"
