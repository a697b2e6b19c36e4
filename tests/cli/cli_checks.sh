#!/usr/bin/env bash
# The torsion tool as a user runs it: one check per call, named by its first argument.
#   cli_checks.sh CASE TORSION ASSETS_DIR [HAPTIC_PEER] [DEVICE_PLUGIN] [FAULTY_PLUGIN]
# Exit 0: pass; 77: skipped (e.g. no tetgen on PATH; CTest SKIP_RETURN_CODE); anything else: fail.
# Each case works in a fresh temporary directory, removed afterwards. TORSION_BULLET_PRECISION
# (double or float, set by CTest) names the Bullet the tool was built on.
set -uo pipefail

case_name=$1
torsion=$2
assets=$3
peer=${4:-}
plugin=${5:-}
faulty_plugin=${6:-}
scenes=$(cd "$(dirname "$0")/../../demos/scenes" && pwd)
# Writes a mesh's copy with its nodes scattered as a mesher's insertion order leaves them.
scatter_mesh=$(cd "$(dirname "$0")/../bench" && pwd)/scatter_mesh.sh

work_name=torsion-cli-test
source "$(dirname "$0")/case_helpers.sh"

expect_rc() {  # expect_rc 0|nonzero
  if [[ $1 == 0 && $rc -ne 0 ]]; then fail "exit code $rc, expected 0"; fi
  if [[ $1 == nonzero && $rc -eq 0 ]]; then fail "exit code 0, expected non-zero"; fi
}

# Value of one `torsion mesh info` field, e.g. info_field tets FILE.
info_field() {
  "$torsion" mesh info "$2" | sed -n "s/^$1 \{1,\}\([^ ]*\).*/\1/p"
}

need_tetgen() {
  command -v tetgen >/dev/null 2>&1 ||
    skip "the 'tetgen' command is not on PATH (Debian package 'tetgen')"
}

# A closed cube [0,2]^3 in each surface format (outward triangles).
write_cube_off() {
  cat >"$1" <<'EOF'
OFF
# a cube of side 2
8 6 0
0 0 0
2 0 0
2 2 0
0 2 0
0 0 2
2 0 2
2 2 2
0 2 2
4 0 3 2 1
4 4 5 6 7
4 0 1 5 4
4 1 2 6 5
4 2 3 7 6
4 3 0 4 7
EOF
}

# An octahedron with quads-free faces, OBJ with texture/normal indices, a negative (relative)
# index, and lines to ignore.
write_octahedron_obj() {
  cat >"$1" <<'EOF'
# octahedron
mtllib none.mtl
o octahedron
v 1 0 0
v -1 0 0
v 0 1 0
v 0 -1 0
v 0 0 1
v 0 0 -1
vt 0 0
vn 0 0 1
s off
usemtl default
f 1/1/1 3/1/1 5/1/1
f 3//1 2//1 5//1
f 2/1 4/1 5/1
f 4 1 5
f 3 1 6
f 2 3 6
f 4 2 6
f 1 4 -1
EOF
}

# Cube triangles as (v0 v1 v2) corner lists over the corners of write_cube_off.
cube_triangles=("0 3 2" "0 2 1" "4 5 6" "4 6 7" "0 1 5" "0 5 4" "1 2 6" "1 6 5" "2 3 7" "2 7 6"
  "3 0 4" "3 4 7")
cube_corner() {  # cube_corner I -> "x y z"
  local c=("0 0 0" "2 0 0" "2 2 0" "0 2 0" "0 0 2" "2 0 2" "2 2 2" "0 2 2")
  echo "${c[$1]}"
}

write_cube_stl_ascii() {
  {
    echo "solid cube"
    for t in "${cube_triangles[@]}"; do
      echo "  facet normal 0 0 0"
      echo "    outer loop"
      for i in $t; do echo "      vertex $(cube_corner "$i")"; done
      echo "    endloop"
      echo "  endfacet"
    done
    echo "endsolid cube"
  } >"$1"
}

# shellcheck disable=SC2059  # the byte escapes live in the format strings on purpose
write_cube_stl_binary() {
  # Little-endian float32: 0 -> 00 00 00 00, 2 -> 00 00 00 40.
  local f0='\x00\x00\x00\x00' f2='\x00\x00\x00\x40'
  {
    printf 'binary cube%69s' ''                 # 80-byte header
    printf '\x0c\x00\x00\x00'                   # 12 triangles
    for t in "${cube_triangles[@]}"; do
      printf "$f0$f0$f0"                        # normal (unused)
      for i in $t; do
        for x in $(cube_corner "$i"); do
          if [[ $x == 0 ]]; then printf "$f0"; else printf "$f2"; fi
        done
      done
      printf '\x00\x00'                         # attribute byte count
    done
  } >"$1"
}

check_cube_mesh() {  # check_cube_mesh MESH: a valid mesh of volume exactly 8
  local tets volume
  tets=$(info_field tets "$1")
  volume=$(info_field volume "$1")
  [[ -n $tets && $tets -ge 6 ]] || fail "expected at least 6 tets in $1, got '$tets'"
  [[ $volume == 8 ]] || fail "expected volume 8 for the cube in $1, got '$volume'"
  echo "ok: $1: $tets tets, volume $volume"
}

# check_haptic_outputs DIR MODE: the haptic log and stats exist; the wrench written to the device
# is non-zero while the hand holds the cylinder and exactly zero 0.25 s after button 2 (the
# safety filter ramps it down at 300 N/s and 30 N m/s from at most 30 N and 3 N m: 0.1 s).
check_haptic_outputs() {
  local dir=$1 mode=$2
  for f in summary.json wrench.csv haptic_hand.csv; do [[ -s $dir/$f ]] || fail "missing $dir/$f"; done
  grep -q "\"mode\": \"$mode\"" "$dir/summary.json" || fail "$dir/summary.json: no $mode haptics stats"
  for key in achieved_rate_hz period_error_ms wrench_age_ms information_age_ms saturated_ticks; do
    grep -q "\"$key\"" "$dir/summary.json" || fail "$dir/summary.json lacks $key"
  done
  awk -F, '
    NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
    { t = $c["time"]; b = $c["buttons"]
      m = 0; for (k = 0; k < 6; k++) { v = $(c["fx"] + k); if (v < 0) v = -v; if (v > m) m = v }
      if ($c["grabbed"] == 1 && m > 0.1) held++
      if (b == 2 && release == "") release = t
      if (release != "" && t > release + 0.25) { after++; if (m != 0) bad++ } }
    END {
      if (held < 100) { print "only " held " ticks with a wrench while grabbed"; exit 1 }
      if (after < 100) { print "only " after " ticks logged after the release"; exit 1 }
      if (bad > 0) { print bad " ticks with a non-zero wrench after the release"; exit 1 } }
  ' "$dir/haptic_hand.csv" || fail "$dir/haptic_hand.csv: wrench not sane"
  echo "ok: $dir: haptic log and stats"
}

case $case_name in
  info_missing_file)
    run "$torsion" mesh info does_not_exist.node
    expect_rc nonzero
    expect_out "^error: does_not_exist.node: cannot open: No such file or directory"
    ;;

  info_malformed_file)
    printf '4 3 0 0\n0 0 0 0\n1 1 0 0\n2 0 x 0\n3 0 0 1\n' >bad.node
    printf '1 4 0\n0 0 1 2 3\n' >bad.ele
    run "$torsion" mesh info bad.node
    expect_rc nonzero
    expect_out "^error: bad.node:4: .*'x'"
    ;;

  convert_round_trip)
    cp "$assets/cylinder_2430.node" "$assets/cylinder_2430.ele" .
    for step in "cylinder_2430.node a.msh" "a.msh b.vtk" "b.vtk c.node"; do
      # shellcheck disable=SC2086
      run "$torsion" mesh convert $step
      expect_rc 0
    done
    for f in a.msh b.vtk c.node; do
      [[ $(info_field tets "$f") == 2408 && $(info_field nodes "$f") == 661 ]] ||
        fail "$f: counts changed in the round trip"
    done
    cmp c.node cylinder_2430.node || fail "node file differs after .node -> .msh -> .vtk -> .node"
    cmp c.ele cylinder_2430.ele || fail "ele file differs after .node -> .msh -> .vtk -> .node"
    ;;

  convert_reorder)
    # Renumbering keeps the body (counts, volume, bounds) and brings the node numbers of each tet
    # together: the committed cylinder is in that order already, a scattered copy is not.
    cp "$assets/cylinder_2430.node" "$assets/cylinder_2430.ele" .
    run "$torsion" mesh convert --reorder cylinder_2430.node r.node
    expect_rc 0
    expect_out "^node order +reverse Cuthill-McKee: mean index span per tet [0-9.]+ -> [0-9.]+$"
    for field in nodes tets volume "bounds min" "bounds max" "surface triangles"; do
      [[ $(info_field "$field" r.node) == $(info_field "$field" cylinder_2430.node) ]] ||
        fail "$field changed by --reorder"
    done
    # Scatter the nodes (node i -> i * 263 mod 661) and reorder: the span must shrink 4-fold.
    "$scatter_mesh" cylinder_2430.node s.node 263
    run "$torsion" mesh convert --reorder s.node t.node
    expect_rc 0
    read -r before after < <(sed -nE 's/^node order .* per tet ([0-9.]+) -> ([0-9.]+)$/\1 \2/p' <<<"$out")
    awk -v b="$before" -v a="$after" 'BEGIN { exit !(b > 4 * a) }' ||
      fail "mean index span $before -> $after: not brought 4-fold closer"
    [[ $(info_field tets t.node) == 2408 && $(info_field volume t.node) == $(info_field volume cylinder_2430.node) ]] ||
      fail "the scattered and reordered mesh is not the same body"
    ;;

  cylinder_small)
    need_tetgen
    run "$torsion" mesh cylinder --radius 0.5 --length 2 --tets 500 -o small.vtk
    expect_rc 0
    expect_out "^wrote small.vtk: cylinder radius 0.5 length 2, [0-9]+ tets \(target 500"
    tets=$(info_field tets small.vtk)
    ((tets >= 485 && tets <= 515)) || fail "$tets tets, not within 3% of 500"
    run "$torsion" mesh info small.vtk
    expect_out "bounds min +-0.[0-9]+ -0.[0-9]+ 0$"
    expect_out "bounds max +0.5 0.[0-9]+ 2$"
    # Deterministic: the same arguments give the same file.
    "$torsion" mesh cylinder --radius 0.5 --length 2 --tets 500 -o again.vtk >/dev/null ||
      fail "second run failed"
    cmp small.vtk again.vtk || fail "two runs with the same arguments differ"
    ;;

  cylinder_unreachable)
    need_tetgen
    run "$torsion" mesh cylinder --radius 1 --length 10 --tets 6 -o c.node
    expect_rc nonzero
    expect_out "^error: torsion mesh cylinder: could not get within 3% of 6 tets: the closest count found was [0-9]+"
    [[ ! -e c.node ]] || fail "wrote a mesh anyway"
    ;;

  cylinder_without_tetgen)
    run env PATH="$work/empty" "$torsion" mesh cylinder --radius 1 --length 10 --tets 500 -o c.node
    expect_rc nonzero
    expect_out "^error: torsion mesh cylinder: needs the 'tetgen' command \(Debian package 'tetgen'\); it is not on PATH$"
    [[ ! -e c.node ]] || fail "wrote a mesh anyway"
    ;;

  cylinder_bad_arguments)
    run "$torsion" mesh cylinder --radius -1 --length 10 --tets 500 -o c.node
    expect_rc nonzero
    expect_out "^error: torsion mesh cylinder: --radius must be a positive number, got -1"
    run "$torsion" mesh cylinder --radius 1 --length 0 --tets 500 -o c.node
    expect_rc nonzero
    expect_out "^error: torsion mesh cylinder: --length must be a positive number, got 0"
    run "$torsion" mesh cylinder --radius 1 --length 10 --tets 5 -o c.node
    expect_rc nonzero
    expect_out "^error: torsion mesh cylinder: --tets must be between 6 and"
    run "$torsion" mesh cylinder --radius 1 --length 10 --tets 500 -o c.stl
    expect_rc nonzero
    expect_out "^error: c.stl: unknown mesh format '.stl'"
    run "$torsion" mesh cylinder --radius 1 --length 10 --tets 500 -o c.node --mesher gmsh
    expect_rc nonzero
    expect_out "unknown --mesher 'gmsh' \(known: tetgen\)"
    ;;

  tetrahedralize_off)
    need_tetgen
    write_cube_off cube.off
    run "$torsion" mesh tetrahedralize cube.off -o cube.msh
    expect_rc 0
    expect_out "^wrote cube.msh: [0-9]+ tets"
    check_cube_mesh cube.msh
    ;;

  tetrahedralize_obj)
    need_tetgen
    write_octahedron_obj octa.obj
    run "$torsion" mesh tetrahedralize octa.obj -o octa.node --max-volume 0.05 --quality 1.5
    expect_rc 0
    volume=$(info_field volume octa.node)
    [[ $volume == 1.33333 ]] || fail "octahedron volume $volume, expected 1.33333"
    tets=$(info_field tets octa.node)
    ((tets >= 27)) || fail "--max-volume 0.05 should give at least 27 tets, got $tets"
    ;;

  tetrahedralize_stl_ascii)
    need_tetgen
    write_cube_stl_ascii cube.stl
    run "$torsion" mesh tetrahedralize cube.stl -o cube.vtk
    expect_rc 0
    expect_out "from cube.stl: 8 vertices, 12 triangles"
    check_cube_mesh cube.vtk
    ;;

  tetrahedralize_stl_binary)
    need_tetgen
    write_cube_stl_binary cube.stl
    [[ $(stat -c %s cube.stl) == 684 ]] || fail "test bug: binary STL of $(stat -c %s cube.stl) bytes"
    run "$torsion" mesh tetrahedralize cube.stl -o cube.node
    expect_rc 0
    expect_out "from cube.stl: 8 vertices, 12 triangles"
    check_cube_mesh cube.node
    ;;

  tetrahedralize_self_intersecting)
    need_tetgen
    # Two closed tetrahedra that overlap.
    cat >two.off <<'EOF'
OFF
8 8 0
0 0 0
2 0 0
0 2 0
0 0 2
0.5 0.5 0.5
2.5 0.5 0.5
0.5 2.5 0.5
0.5 0.5 2.5
3 0 2 1
3 0 1 3
3 0 3 2
3 1 2 3
3 4 6 5
3 4 5 7
3 4 7 6
3 5 6 7
EOF
    run "$torsion" mesh tetrahedralize two.off -o two.node
    expect_rc nonzero
    expect_out "^error: torsion mesh tetrahedralize: two.off: tetgen .* failed"
    expect_out "two.off: the surface intersects itself"
    expect_out "two.off:14 and two.off:1[5-7]"
    ;;

  tetrahedralize_open_surface)
    write_cube_off cube.off
    sed -i 's/^8 6 0$/8 5 0/; $d' cube.off  # drop the last face
    run "$torsion" mesh tetrahedralize cube.off -o cube.node
    expect_rc nonzero
    expect_out "^error: cube.off:[0-9]+: the surface is not closed: 4 edge\(s\) used by one triangle"
    ;;

  tetrahedralize_malformed)
    printf 'OFF\n4 4 0\n0 0 0\n1 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 3\n3 0 2 3\n3 1 2 3\n' >a.off
    run "$torsion" mesh tetrahedralize a.off -o a.node
    expect_rc nonzero
    expect_out "^error: a.off:4: vertex 1: expected 3 coordinates, got 2$"

    printf 'OFF\n4 4 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n3 0 1 4\n' >b.off
    run "$torsion" mesh tetrahedralize b.off -o b.node
    expect_rc nonzero
    expect_out "^error: b.off:8: face 1: vertex index 4 out of range \(4 vertices, 0-based\)$"

    printf 'OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n' >c.off
    run "$torsion" mesh tetrahedralize c.off -o c.node
    expect_rc nonzero
    expect_out "^error: c.off:7: unexpected end of file, expected face 1 of 2$"

    printf 'v 0 0 0\nv 1 0 0\nv 0 1 0\n# comment\nf 1 2 9\n' >d.obj
    run "$torsion" mesh tetrahedralize d.obj -o d.node
    expect_rc nonzero
    expect_out "^error: d.obj:5: face corner '9': vertex index 9 out of range \(3 vertices read so far\)$"

    printf 'v 0 0 0\nv 1 zero 0\n' >e.obj
    run "$torsion" mesh tetrahedralize e.obj -o e.node
    expect_rc nonzero
    expect_out "^error: e.obj:2: expected a number for y, got 'zero'$"

    printf 'solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\nendfacet\nendsolid s\n' >f.stl
    run "$torsion" mesh tetrahedralize f.stl -o f.node
    expect_rc nonzero
    expect_out "^error: f.stl:7: expected 'endloop' \(STL facets are triangles\), got 'endfacet'$"

    printf 'binary junk header that is not a solid' >g.stl
    run "$torsion" mesh tetrahedralize g.stl -o g.node
    expect_rc nonzero
    expect_out "^error: g.stl: not an STL file"

    printf 'ply\n' >h.ply
    run "$torsion" mesh tetrahedralize h.ply -o h.node
    expect_rc nonzero
    expect_out "^error: h.ply: no 'end_header' line$"

    printf 'solid\n' >i.wrl
    run "$torsion" mesh tetrahedralize i.wrl -o i.node
    expect_rc nonzero
    expect_out "^error: i.wrl: unknown surface format '.wrl' \(known: .off, .obj, .stl, .ply\)$"

    run "$torsion" mesh tetrahedralize missing.off -o m.node
    expect_rc nonzero
    expect_out "^error: missing.off: cannot open: No such file or directory$"
    ;;

  tetrahedralize_without_tetgen)
    write_cube_off cube.off
    run env PATH="$work/empty" "$torsion" mesh tetrahedralize cube.off -o cube.node
    expect_rc nonzero
    expect_out "^error: torsion mesh tetrahedralize: needs the 'tetgen' command \(Debian package 'tetgen'\); it is not on PATH$"
    ;;

  run_twist)
    # A short twist of the small cylinder: runs, reports, writes every output.
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    run "$torsion" run twist.json --out out --steps 40 --threads 1
    expect_rc 0
    expect_out "body 'cylinder': 661 nodes, 2408 tets"
    expect_out "done: 40 steps; results in out/"
    for f in summary.json wrench.csv energy.csv cylinder.vtk; do [[ -s out/$f ]] || fail "missing out/$f"; done
    grep -q '"stable": true' out/summary.json || fail "summary does not say stable"
    grep -q '"steps": 40' out/summary.json || fail "summary does not count 40 steps"
    [[ $(wc -l < out/wrench.csv) -eq 41 ]] || fail "wrench.csv should have a header and 40 rows"
    head -1 out/wrench.csv | grep -q "hand.tz" || fail "wrench.csv lacks the hand's torque"
    # The turned end feels a restoring torque: negative about +z once it has turned.
    awk -F, 'NR == 41 { for (i = 1; i <= NF; i++) if (col[i] == "hand.tz") exit !($i < 0) }
             NR == 1 { for (i = 1; i <= NF; i++) col[i] = $i }' out/wrench.csv || fail "hand torque not restoring"
    "$torsion" mesh info out/cylinder.vtk > /dev/null || fail "the final mesh does not read back"
    ;;

  run_node_order)
    # A mesh in a mesher's scattered order is renumbered inside (node_order "cache_friendly", the
    # default) and is the same body: its outputs keep the file's numbers, its motion agrees with
    # node_order "file" to rounding, and the series' first frame is the same file.
    "$scatter_mesh" "$assets/cylinder_2430.node" s.node 263
    for order in cache_friendly file; do
      sed -e "s|../../assets/meshes/cylinder_2430.node|s.node|" \
          -e "s|\"name\": \"cylinder\", \"mesh\"|\"name\": \"cylinder\", \"node_order\": \"$order\", \"mesh\"|" \
          "$scenes/twist_cylinder_2430.json" >$order.json
      grep -q "\"node_order\": \"$order\"" $order.json || fail "could not set node_order in the scene"
      run "$torsion" run $order.json --out $order --steps 30 --vtk-every 10 --threads 1
      expect_rc 0
    done
    grep -q '"renumbered": true' cache_friendly/summary.json || fail "the scattered mesh was not renumbered"
    grep -q '"renumbered": false' file/summary.json || fail "node_order file renumbered the mesh"
    cmp <(sed -n '/^CELLS/,/^POINT_DATA/p' cache_friendly/cylinder.vtk) \
        <(sed -n '/^CELLS/,/^POINT_DATA/p' file/cylinder.vtk) || fail "the final mesh's cells differ"
    # Final positions: the sums of a step run in another order, so they agree to rounding (1e-12
    # m on a 10 m bar twisted for 0.3 s), node by node in the file's numbers.
    paste -d ' ' <(sed -n '/^POINTS/,/^CELLS/p' cache_friendly/cylinder.vtk | sed '1d;$d') \
                 <(sed -n '/^POINTS/,/^CELLS/p' file/cylinder.vtk | sed '1d;$d') |
      awk '{ for (i = 1; i <= 3; ++i) { d = $i - $(i + 3); if (d < 0) d = -d; if (d > m) m = d } ++n }
           END { if (n != 661 || m > 1e-12) { print n " points, max difference " m; exit 1 } }' ||
      fail "the final positions differ beyond rounding"
    cmp cache_friendly/series/cylinder_000000.vtu file/series/cylinder_000000.vtu ||
      fail "the series' first frame differs"
    ;;

  run_bad_scene)
    printf '{\n  "steps": 10,\n  "bodies": [{"name": "b", "mesh": "x.node", "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "densty": 1000}}]\n}\n' > bad.json
    run "$torsion" run bad.json --out out
    expect_rc nonzero
    expect_out "^error: bad.json: bodies\\[0\\].material.density: missing \\(required\\); did you mean 'densty'\\?$"
    [[ ! -e out/summary.json ]] || fail "no output may be written for a bad scene"
    ;;

  run_scene_by_name)
    # A demo scene by its name runs from any directory; an unknown name lists the scenes.
    run "$torsion" run press --out out --steps 3 --threads 1
    expect_rc 0
    expect_out "done: 3 steps; results in out/"
    run "$torsion" run no_such_scene --out out2
    expect_rc nonzero
    expect_out "^error: no_such_scene: no such scene file, and no scene of that name in .*demos/scenes \\(scenes:.* press .*twist_cylinder_2430.*\\)$"
    [[ ! -e out2 ]] || fail "no output may be written for an unknown scene"
    ;;

  run_missing_mesh)
    printf '{"bodies": [{"name": "b", "mesh": "nowhere.node", "material": {"youngs_modulus": 1e5, "poisson_ratio": 0.3, "density": 1000}}]}' > s.json
    run "$torsion" run s.json --out out
    expect_rc nonzero
    expect_out "^error: s.json: bodies\\[0\\] 'b': .*nowhere.node: cannot open"
    ;;

  run_hand_misses)
    # A hand whose plane misses the body: a clear error before any step, nothing written.
    sed "s|../../assets/meshes|$assets|; s|\"origin\": \\[0, 0, 9.9\\]|\"origin\": [0, 0, 20]|" \
      "$scenes/twist_cylinder_2430.json" > miss.json
    run "$torsion" run miss.json --out out --steps 5
    expect_rc nonzero
    expect_out "^error: miss.json: hands\\[0\\] 'hand': grab at t = 0 s: .*"
    [[ ! -e out/summary.json ]] || fail "no output may be written when a hand misses"
    ;;

  run_unstable)
    # A speed limit that gravity alone exceeds: the run must stop, say where, and exit 3.
    sed "s|../../assets/meshes|$assets|; s|\"gravity\": \\[0, 0, 0\\]|\"gravity\": [0, 0, -9.81]|; s|\"tolerance\": 1e-4|\"tolerance\": 1e-4, \"max_speed\": 0.05|" \
      "$scenes/twist_cylinder_2430.json" > unstable.json
    run "$torsion" run unstable.json --out out --steps 200 --threads 1
    [[ $rc -eq 3 ]] || fail "exit code $rc, expected 3"
    expect_out "^error: simulation unstable: body 'cylinder', step [0-9]+: blow-up: a node moves at"
    grep -q '"stable": false' out/summary.json || fail "summary does not say unstable"
    ! grep -qi nan out/cylinder.vtk || fail "NaN written to the final mesh"
    ;;

  run_twist_past_kink)
    # The small cylinder twisted at 1 rad/s to 4.8 pi: it kinks near 4 pi and, without
    # self-contact, passes through itself. The run is still "stable" but warns and lists the
    # anomalies; with --stop-on-anomaly it stops at the first one with exit code 4. The volume
    # barrier is turned off (barrier_threshold 0) so that the crease's tets invert, as they do in
    # the plain corotated material: the inverted-tet warning is what this checks.
    sed "s|../../assets/meshes|$assets|; s|\"angular_velocity\": \\[0, 0, 0.1\\]|\"angular_velocity\": [0, 0, 1]|; s|\"duration\": 62.83185307179586|\"duration\": 15|; s|\"stiffness_damping\": 0.01}|\"stiffness_damping\": 0.01, \"barrier_threshold\": 0}|" \
      "$scenes/twist_cylinder_2430.json" > kink.json
    run "$torsion" run kink.json --out out --steps 1500 --threads 1
    expect_rc 0
    expect_out "warning: body 'cylinder', step [0-9]+: [0-9]+ inverted tets \\(det F <= 0\\)"
    expect_out "warning: body 'cylinder', step [0-9]+: kinetic energy .* stored energy released"
    grep -q '"kind": "inverted_elements"' out/summary.json || fail "summary lacks inverted_elements"
    grep -q '"kind": "energy_release"' out/summary.json || fail "summary lacks energy_release"
    grep -q '"stable": true' out/summary.json || fail "summary does not say stable"
    run "$torsion" run kink.json --out stop --steps 1500 --threads 1 --stop-on-anomaly
    [[ $rc -eq 4 ]] || fail "exit code $rc, expected 4"
    expect_out "^error: stopped at the first anomaly: body 'cylinder', step [0-9]+: "
    grep -q '"stopped_on_anomaly": true' stop/summary.json || fail "summary does not say stopped"
    ! grep -q '"steps": 1500,' stop/summary.json || fail "the stopped run did all its steps"
    ;;

  run_haptic_scripted_replay)
    # A scripted device drives the cylinder's hand from the CLI (lockstep haptics); its loop log
    # is then replayed as a device and must reproduce the run.
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    write_short_turn turn.json
    run "$torsion" run twist.json --device hand=scripted:turn.json --out rec --steps 120 --threads 1
    expect_rc 0
    expect_out "hand 'hand': device scripted\(turn.json\), lockstep haptic loop at 1000 Hz"
    check_haptic_outputs rec lockstep
    run "$torsion" run twist.json --device hand=replay:rec/haptic_hand.csv --out rep --steps 120 --threads 1
    expect_rc 0
    expect_out "hand 'hand': device replay\(haptic_hand.csv\), lockstep"
    check_haptic_outputs rep lockstep
    # Same poses at the same ticks: the hand's torque at the end of the grab (step 70) agrees to
    # 1e-4 relative (the log keeps 10 significant digits of each pose).
    a=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "hand.tz") c = i } NR == 71 { print $c }' rec/wrench.csv)
    b=$(awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == "hand.tz") c = i } NR == 71 { print $c }' rep/wrench.csv)
    awk -v a="$a" -v b="$b" 'BEGIN { d = a - b; if (d < 0) d = -d; m = a < 0 ? -a : a;
      exit !(m > 1 && d <= 1e-4 * m) }' || fail "replayed torque $b differs from recorded $a"
    ;;

  run_haptic_tool_devices)
    # The palpation probe (a tool: a rigid body on a virtual coupling) held by each kind of
    # device the scene's own scripted one is not: its scripted run's loop log replayed, the
    # simulated-arm plug-in pushing it, and the reference peer over UDP.
    [[ -f $plugin && -x $peer ]] || fail "no device plug-in or peer given"
    sed -e "s|../../assets/meshes|$assets|" -e "s|../../assets/trajectories|$assets/../trajectories|" \
      "$scenes/palpation.json" > palpation.json
    probe_at() {  # probe_at DIR COLUMN: the probe's COLUMN (x, z) at the last step, rigid.csv
      awk -F, -v col="probe.$2" 'NR == 1 { for (i = 1; i <= NF; i++) if ($i == col) c = i }
        END { print $c }' "$1/rigid.csv"
    }
    # 1. Replay: the same poses at the same ticks bring the probe to the same place (the log
    #    keeps 10 significant digits of each pose): pressed 8.7 mm into the organ by t = 1.5 s.
    run "$torsion" run palpation.json --out rec --steps 150 --threads 1
    expect_rc 0
    run "$torsion" run palpation.json --device probe=replay:rec/haptic_probe.csv --out rep \
      --steps 150 --threads 1
    expect_rc 0
    expect_out "tool 'probe': device replay\(haptic_probe.csv\), lockstep"
    for c in x z; do
      awk -v a="$(probe_at rec $c)" -v b="$(probe_at rep $c)" 'BEGIN { d = a - b; if (d < 0) d = -d
        exit !(d <= 1e-7) }' || fail "replayed probe.$c $(probe_at rep $c) differs from $(probe_at rec $c)"
    done
    awk -v z="$(probe_at rec z)" 'BEGIN { exit !(z < 0.040) }' ||
      fail "the scripted probe did not press into the organ (z = $(probe_at rec z), from 0.045)"
    # 2. The plug-in's simulated operator pushes the handle 0.05 m/s along x for 0.4 s: the probe,
    #    in free space above the organ, follows the 2 cm within a tenth (the arm's own dynamics
    #    and the coupling's lag of a few ms are all that differ).
    config="intent=push,intent_rate=0.05,intent_start=0.1,intent_time=0.4"
    run "$torsion" run palpation.json --device "probe=plugin:$plugin:$config" --haptics lockstep \
      --out plug --steps 100 --threads 1
    expect_rc 0
    expect_out "tool 'probe': device plugin\(libtorsion_simulated_device.so: simulated"
    grep -q '"late": 0' plug/summary.json || fail "plug/summary.json: a plug-in read was late"
    awk -v x="$(probe_at plug x)" 'BEGIN { d = x + 0.03 - 0.02; if (d < 0) d = -d; exit !(d <= 0.002) }' ||
      fail "the plug-in moved the probe to x = $(probe_at plug x), expected -0.03 + 0.02"
    # 3. The reference peer plays the scene's own trajectory over UDP (threaded haptics): the
    #    probe presses into the organ and the peer receives the contact force.
    port=$((20000 + RANDOM % 20000))
    "$torsion" run palpation.json --device "probe=network:$port" --out net --steps 150 \
      --threads 1 >torsion.log 2>&1 &
    sim=$!
    wait_for_network_device torsion.log
    grep -q "tool 'probe': device network(udp port $port), threaded haptic loop" torsion.log ||
      { kill "$sim"; cat torsion.log; fail "torsion did not open the network device"; }
    "$peer" --trajectory "$assets/../trajectories/palpation.json" --port "$port" --log peer.csv ||
      fail "the peer failed"
    wait "$sim"
    rc=$?
    out=$(cat torsion.log)
    printf '%s\n' "$out"
    expect_rc 0
    grep -q '"accepted": [1-9][0-9][0-9]' net/summary.json || fail "fewer than 100 poses accepted"
    awk -v z="$(probe_at net z)" 'BEGIN { exit !(z < 0.040) }' ||
      fail "the networked probe did not press into the organ (z = $(probe_at net z))"
    # The organ pushes the probe up: packets whose force along z exceeds 0.1 N.
    awk -F, 'NR > 1 && $4 > 0.1 { found = 1 } END { exit !found }' peer.csv ||
      fail "the peer never received the contact force"
    ;;

  run_haptic_sim_priority)
    # --sim-priority asks real-time priority for the stepping thread under threaded haptics: the
    # summary says what was asked and whether it was granted, and a refusal (no privilege) is a
    # warning, not a failure. Out of range (the loops run at 80) is an error before any step.
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    write_short_turn turn.json
    run "$torsion" run twist.json --device hand=scripted:turn.json --haptics threaded \
      --sim-priority 40 --out rt --steps 60 --threads 1
    expect_rc 0
    tr -d ' \n' < rt/summary.json > flat.json
    grep -q '"simulation_priority":{"asked":40,"real_time":true}' flat.json ||
      { grep -q '"simulation_priority":{"asked":40,"real_time":false}' flat.json &&
        grep -q "sim-priority 40: real-time priority refused" <<<"$out"; } ||
      fail "summary lacks the priority asked and granted (or the refusal's warning)"
    run "$torsion" run twist.json --device hand=scripted:turn.json --haptics threaded \
      --sim-priority 80 --out bad --steps 5
    expect_rc nonzero
    expect_out "--sim-priority: 80 is not in \[0, 79\]"
    [[ ! -e bad/summary.json ]] || fail "a refused option may not leave a summary"
    ;;

  run_haptic_network)
    # The reference peer plays a trajectory over UDP loopback; torsion drives the hand with it
    # (threaded haptics: the loop at 1 kHz on its own thread, the simulation paced to the clock).
    [[ -x $peer ]] || fail "no torsion_haptic_peer given"
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    write_short_turn turn.json
    port=$((20000 + RANDOM % 20000))
    "$torsion" run twist.json --device "hand=network:$port" --out net --steps 200 --threads 1 \
      >torsion.log 2>&1 &
    sim=$!
    wait_for_network_device torsion.log
    grep -q "hand 'hand': device network(udp port $port), threaded haptic loop" torsion.log ||
      { kill "$sim"; cat torsion.log; fail "torsion did not open the network device"; }
    "$peer" --trajectory turn.json --port "$port" --log peer.csv || fail "the peer failed"
    wait "$sim"
    rc=$?
    out=$(cat torsion.log)
    printf '%s\n' "$out"
    expect_rc 0
    check_haptic_outputs net threaded
    grep -q '"accepted": [1-9][0-9][0-9]' net/summary.json || fail "fewer than 100 poses accepted"
    # The peer received the wrench: some packet carried a torque about z.
    awk -F, 'NR > 1 && ($7 > 0.1 || $7 < -0.1) { found = 1 } END { exit !found }' peer.csv ||
      fail "the peer never received a non-zero torque"
    ;;

  run_haptic_bad_device)
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    run "$torsion" run twist.json --device hand=network:5750 --haptics lockstep --out out --steps 5
    expect_rc nonzero
    expect_out "^error: twist.json: hands\[0\] 'hand': device: a network device lives in wall-clock time and cannot tick in lockstep: use --haptics threaded$"
    run "$torsion" run twist.json --device hand=scripted:missing.json --out out --steps 5
    expect_rc nonzero
    expect_out "^error: twist.json: hands\[0\] 'hand': device: missing.json: cannot open: No such file or directory$"
    run "$torsion" run twist.json --device foot=spacemouse --out out --steps 5
    expect_rc nonzero
    expect_out "^error: --device 'foot=spacemouse': the scene has no hand or dynamic rigid body named 'foot' \(hands: 'hand'\)$"
    # No spacenavd runs here: the SpaceMouse says what is missing (daemon, or libspnav itself).
    if [[ ! -e /var/run/spnav.sock ]]; then
      run "$torsion" run twist.json --device hand=spacemouse --out out --steps 5
      expect_rc nonzero
      expect_out "^error: twist.json: hands\[0\] 'hand': device: SpaceMouse: (cannot connect to the spacenavd daemon|this build of Torsion has no libspnav)"
    fi
    [[ ! -e out/summary.json ]] || fail "no output may be written when a device cannot open"
    ;;

  run_haptic_manual)
    # A manual device is moved by `torsion view`'s mouse and keys: `torsion run` has none and
    # refuses it, from --device or from the scene file, naming the tool, before any output.
    run "$torsion" run "$scenes/palpation.json" --device probe=manual --out out --steps 5
    expect_rc nonzero
    expect_out "^error: .*palpation\.json: device 'manual' of tool 'probe' is moved by the mouse and keys of torsion view, which this run has not: use scripted, replay, network, spacemouse or plugin$"
    sed -e "s|../../assets|$assets/..|" \
        -e 's|"type": "scripted", "trajectory": "[^"]*",|"type": "manual",|' \
        "$scenes/palpation.json" > manual.json
    grep -q '"type": "manual"' manual.json || fail "manual.json: the device was not replaced"
    run "$torsion" run manual.json --out out --steps 5
    expect_rc nonzero
    expect_out "^error: manual\.json: device 'manual' of tool 'probe' is moved by the mouse and keys of torsion view, which this run has not: use scripted, replay, network, spacemouse or plugin$"
    # Manual devices move tools; the viewer's M key takes a hand.
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    run "$torsion" run twist.json --device hand=manual --out out --steps 5
    expect_rc nonzero
    expect_out "^error: --device 'hand=manual': manual moves a tool \(a dynamic rigid body\); torsion view's M key takes hand 'hand'$"
    [[ ! -e out ]] || fail "no output may be written when a device is refused"
    ;;

  run_haptic_plugin)
    # The example device plug-in (a simulated arm whose operator turns the wrist 0.3 rad, presses
    # button 2 at 0.8 s) loaded at run time, ticking in lockstep; then a wrong library.
    [[ -f $plugin ]] || fail "no device plug-in given"
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    config="intent=twist,intent_rate=0.5,intent_start=0.05,intent_time=0.6,release_time=0.8"
    run "$torsion" run twist.json --device "hand=plugin:$plugin:$config" --haptics lockstep \
      --out plug --steps 120 --threads 1
    expect_rc 0
    expect_out "hand 'hand': device plugin\(libtorsion_simulated_device.so: simulated 0.3 kg, 200 Hz motors, 0 ms delay\), lockstep"
    check_haptic_outputs plug lockstep
    grep -q '"late": 0' plug/summary.json || fail "plug/summary.json: a plug-in read was late"
    grep -q '"reads": [1-9][0-9][0-9]' plug/summary.json || fail "fewer than 100 plug-in reads"
    grep -q '"dissipated_J"' plug/summary.json || fail "plug/summary.json: no passivity entry"
    head -1 plug/haptic_hand.csv | grep -q ",port_energy,pc_alpha,information_age_ms$" || fail "no passivity and information-age columns"
    # Named without a directory: the plug-in built (and installed) with Torsion, here with a
    # 20 ms link delay each way.
    run "$torsion" run twist.json --device "hand=plugin:libtorsion_simulated_device.so:$config,delay=0.02" \
      --haptics lockstep --out delayed --steps 20 --threads 1
    expect_rc 0
    expect_out "hand 'hand': device plugin\(libtorsion_simulated_device.so: simulated 0.3 kg, 200 Hz motors, 20 ms delay\), lockstep"
    run "$torsion" run twist.json --device "hand=plugin:$assets/cylinder_2430.node" --out bad --steps 5
    expect_rc nonzero
    expect_out "^error: twist.json: hands\[0\] 'hand': device: .*cylinder_2430.node: cannot load the device plug-in: "
    ;;

  run_haptic_plugin_crash)
    # A plug-in that segfaults 50 ms into the run, isolated in its device host (the default): the
    # run goes on to its end, the host's death is reported once and in the summary, the device is
    # dead from then on and its output zero once held (5 ms) and faded (0.2 s); no host is left.
    [[ -f $faulty_plugin ]] || fail "no faulty device plug-in given"
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > twist.json
    run "$torsion" run twist.json --device "hand=plugin:$faulty_plugin:fault=segv,after=0.05" \
      --haptics lockstep --out crash --steps 40 --threads 1
    expect_rc 0
    expect_out "^done: 40 steps"
    [[ $(grep -c "warning: the device host of .*libtorsion_faulty_device.so killed by signal 11 (SIGSEGV); the device is dead" <<< "$out") -eq 1 ]] ||
      fail "the host's death was not reported exactly once"
    grep -q '"host_exit": "killed by signal 11 (SIGSEGV)"' crash/summary.json ||
      fail "crash/summary.json: no host_exit"
    grep -q '"isolated": true' crash/summary.json || fail "crash/summary.json: not isolated"
    grep -q '"dead": [1-9]' crash/summary.json || fail "crash/summary.json: the device never died"
    awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next }
      $c["time"] > 0.05 + 0.005 + 0.2 + 0.002 {
        n++; if ($c["alive"] != 0) bad++
        for (k = 0; k < 6; k++) if ($(c["fx"] + k) != 0) bad++ }
      END { exit !(n >= 100 && bad == 0) }' crash/haptic_hand.csv ||
      fail "crash/haptic_hand.csv: the device is not dead with a zero output after the fade"
    pgrep -f "torsion_device_host .*libtorsion_faulty_device.so fault=segv,after=0.05" &&
      fail "a device host outlived torsion"
    # The same plug-in in process ("isolated": false): the scene key, and what a typo in it says.
    /usr/bin/python3 - "$faulty_plugin" <<'PY'
import json, sys
scene = json.load(open("twist.json"))
hand = scene["hands"][0]
del hand["motion"]
hand["device"] = {"type": "plugin", "library": sys.argv[1], "isolated": False}
json.dump(scene, open("inproc.json", "w"))
hand["device"]["isolated"] = "yes"
json.dump(scene, open("typo.json", "w"))
PY
    run "$torsion" run inproc.json --haptics lockstep --out inproc --steps 10 --threads 1
    expect_rc 0
    grep -q '"isolated": false' inproc/summary.json || fail "inproc/summary.json: not in process"
    run "$torsion" run typo.json --haptics lockstep --out typo --steps 10 --threads 1
    expect_rc nonzero
    expect_out "^error: typo.json: hands\[0\]\.device\.isolated: expected true or false"
    ;;

  run_press)
    # The kinematic press: runs stable, writes rigid.csv (the plate on its script) and contact
    # figures with no node left inside the plate or the ground.
    sed "s|../../assets/meshes|$assets|" "$scenes/press.json" > press.json
    run "$torsion" run press.json --out out --steps 80 --threads 1
    expect_rc 0
    expect_out "done: 80 steps; results in out/ \\(summary.json, wrench.csv, energy.csv, rigid.csv,"
    [[ $(wc -l < out/rigid.csv) -eq 81 ]] || fail "rigid.csv should have a header and 80 rows"
    head -1 out/rigid.csv | grep -q "^step,time,plate.x,plate.y,plate.z,plate.qx" || fail "rigid.csv header"
    # Down at 0.1 m/s for 0.6 s from 0.26: at step 80 (t = 0.8 s) it holds at 0.2, as exactly as
    # Bullet stores a pose (float Bullet: 0.2 -> 0.200000003, 1.2e-7 relative).
    tol=1e-9
    [[ ${TORSION_BULLET_PRECISION:-double} == float ]] && tol=2.4e-8
    awk -F, -v tol="$tol" 'NR == 81 { exit !($5 > 0.2 - tol && $5 < 0.2 + tol) }' out/rigid.csv ||
      fail "the plate is not on its script"
    python3 - out/summary.json <<'PY' || fail "contact figures"
import json, sys
c = json.load(open(sys.argv[1]))["contacts"]
assert c["active_max"] >= 32 and c["normal_impulse_total_Ns"] > 0, c
# The convex solve's near-rigid contacts: 0.20 mm under a 6 cm press (contact_physics_test.cpp).
assert c["max_penetration_m"] < 3e-4 and c["unconverged_steps"] == 0, c
PY
    ;;

  run_soft_stack)
    # Contact between FEM bodies: three soft blocks stacked on the ground and a soft ball dropped
    # on them run from the CLI by name; summary.json reports the FEM-FEM contacts of every step
    # (the stack touches from the start) and the ball lands (more contacts once it does).
    run "$torsion" run soft_stack --out out --steps 60 --threads 1
    expect_rc 0
    python3 - out/summary.json <<'PY' || fail "fem_contact figures"
import json, sys
c = json.load(open(sys.argv[1]))["contacts"]["fem_contact"]
assert c["steps_in_contact"] == 60 and c["active_max"] > 0, c
assert c["normal_impulse_total_Ns"] > 0, c
PY
    ;;

  run_bullet_collide_soft)
    # Two soft cubes thrown at each other at 15 m/s each (starting velocities from the scene):
    # they meet, every contact step converges and the end gaps stay within the tolerance.
    run "$torsion" run bullet_collide_soft --out out --threads 1
    expect_rc 0
    python3 - out/summary.json <<'PY' || fail "fem_contact figures"
import json, sys
c = json.load(open(sys.argv[1]))["contacts"]["fem_contact"]
assert c["steps_in_contact"] > 0 and c["normal_impulse_total_Ns"] > 0, c
assert c["unconverged_steps"] == 0 and c["max_end_penetration_m"] < 2.3e-3, c
PY
    ;;

  run_bad_body_velocity)
    # A starting speed beyond the bound: refused before any step, naming the file and the key.
    sed "s|../../assets/meshes|$assets|; s|\"linear_velocity\": \[0, 0, -15\]|\"linear_velocity\": [0, 0, -2e6]|" \
      "$scenes/bullet_collide_moving.json" > bad.json
    run "$torsion" run bad.json --out out
    expect_rc nonzero
    expect_out "^error: bad.json: bodies\\[0\\].linear_velocity: speed 2e\\+06 m/s is above the bound"
    [[ ! -e out/summary.json ]] || fail "no output may be written for a bad scene"
    ;;

  run_bad_rigid_body)
    # A kinematic body with a mass: refused before any step, naming the key.
    sed "s|../../assets/meshes|$assets|; s|\"friction\": 0.8,|\"friction\": 0.8, \"mass\": 3,|" \
      "$scenes/press.json" > bad.json
    run "$torsion" run bad.json --out out
    expect_rc nonzero
    expect_out "^error: bad.json: rigid_bodies\\[0\\].mass: a kinematic body has no mass"
    [[ ! -e out/summary.json ]] || fail "no output may be written for a bad scene"
    ;;

  mesh_box_and_ball)
    run "$torsion" mesh box --min 0 0 0 --max 1 2 0.5 --cells 2 4 1 -o box.node
    expect_rc 0
    [[ $(info_field tets box.node) == 48 ]] || fail "box: 2 x 4 x 1 cells should give 48 tets"
    [[ $(info_field volume box.node) == 1 ]] || fail "box: volume should be 1"
    run "$torsion" mesh ball --radius 0.5 --cells 4 -o ball.vtk
    expect_rc 0
    [[ $(info_field tets ball.vtk) == 384 ]] || fail "ball: 4^3 cells should give 384 tets"
    run "$torsion" mesh box --min 0 0 0 --max 1 0 1 --cells 1 1 1 -o flat.node
    expect_rc nonzero
    expect_out "^error: torsion mesh box: --max must exceed --min"
    ;;

  *)
    fail "unknown case '$case_name'"
    ;;
esac
echo "PASS: $case_name"
