#!/usr/bin/env bash
# What summary.json says about the run's provenance, and `torsion check` comparing two runs: one
# case per call, named by its first argument.
#   check_checks.sh CASE TORSION ASSETS_DIR
# Exit 0: pass; 77: skipped; anything else: fail. Each case works in a fresh temporary directory.
set -uo pipefail

case_name=$1
torsion=$2
assets=$3
scenes=$(cd "$(dirname "$0")/../../demos/scenes" && pwd)

work_name=torsion-check-test
source "$(dirname "$0")/case_helpers.sh"

expect_rc() {
  [[ $rc -eq $1 ]] || fail "exit code $rc, expected $1"
}

# twist RUN_DIR [THREADS] [SED]: 20 steps of the 2430-tet cylinder twisted by its hand.
twist() {
  sed "s|../../assets/meshes|$assets|; ${3:-}" "$scenes/twist_cylinder_2430.json" > "$1.json"
  "$torsion" run "$1.json" --out "$1" --steps 20 --threads "${2:-1}" > /dev/null 2>&1 ||
    fail "the run $1 failed"
}

case $case_name in
  summary_names_version_commit_and_state)
    # summary.json: the schema, the version and commit `torsion --version` prints, the threads
    # used (at least 1, never 0 for "all cores") and a 16-digit hash of the final state that a
    # second identical run reproduces and a different run does not.
    twist a 0
    twist b 0
    twist c 0 's|"youngs_modulus": 1e5|"youngs_modulus": 1.01e5|'
    version=$("$torsion" --version) || fail "--version"
    /usr/bin/python3 - "$version" a/summary.json b/summary.json c/summary.json <<'PY' || fail "summary fields"
import json, re, sys
version = sys.argv[1]
a, b, c = (json.load(open(p)) for p in sys.argv[2:])
assert a["schema_version"] == 1, a["schema_version"]
assert version == "torsion %s (git %s, %s Bullet)" % (a["torsion_version"], a["git_commit"],
                                                       a["bullet_precision"]), (version, a)
assert re.fullmatch(r"[0-9a-f]{12}(-dirty)?|unknown", a["git_commit"]), a["git_commit"]
assert isinstance(a["threads"], int) and a["threads"] >= 1, a["threads"]
assert re.fullmatch(r"[0-9a-f]{16}", a["final_state_hash"]), a["final_state_hash"]
assert a["final_state_hash"] == b["final_state_hash"], "identical runs, different hashes"
assert a["final_state_hash"] != c["final_state_hash"], "a stiffer cylinder, the same hash"
PY
    grep -q '"youngs_modulus": 1.01e5' c.json || fail "the stiffer scene was not made"
    ;;

  check_identical_runs_agree)
    twist a
    twist b
    run "$torsion" check a b
    expect_rc 0
    expect_out "^summary.json: [0-9]+ values compared, 0 differ"
    expect_out "same final_state_hash: the final states are identical bit for bit"
    expect_out "^wrench.csv: 20 rows, 14 columns; largest difference 0 of its kind's scale"
    expect_out "^cylinder.vtk: 661 nodes; largest position difference 0 m"
    expect_out "^same: a matches b within 1e-06 relative, 1e-12 absolute"
    ;;

  check_finds_a_stiffer_material)
    # E 1 % higher: the torque on the hand changes by about 1 %, far beyond 1e-6 of its scale;
    # a 5 % tolerance accepts it.
    twist a
    twist b 1 's|"youngs_modulus": 1e5|"youngs_modulus": 1.01e5|'
    grep -q '"youngs_modulus": 1.01e5' b.json || fail "the stiffer scene was not made"
    run "$torsion" check b a
    expect_rc 2
    expect_out "DIFF wrench.csv hand.tz: [0-9]+ rows differ"
    expect_out "note final_state_hash"
    expect_out "^DIFFERENT: [0-9]+ differences between b and a"
    run "$torsion" check b a --tolerance 0.05
    expect_rc 0
    expect_out "^same: b matches a within 0.05 relative"
    ;;

  check_finds_a_moved_node_and_a_missing_file)
    # One coordinate of the final mesh moved by 1e-4 m (1e-5 of the 10 m cylinder), and a CSV
    # removed: two differences; the moved node is found at 1e-6 and passes at 1e-4.
    twist a
    cp -r a b
    /usr/bin/python3 - b/cylinder.vtk <<'PY' || fail "editing the mesh"
import sys
lines = open(sys.argv[1]).read().split("\n")
i = next(k for k, l in enumerate(lines) if l.startswith("POINTS")) + 8
x = [float(v) for v in lines[i].split()]
x[0] += 1e-4
lines[i] = " ".join("%.17g" % v for v in x)
open(sys.argv[1], "w").write("\n".join(lines))
PY
    rm b/energy.csv
    run "$torsion" check b a
    expect_rc 2
    expect_out "DIFF cylinder.vtk: 661 nodes; largest position difference 0.0001[0-9]* m \\(node 7,"
    expect_out "energy.csv: DIFF missing from the run"
    expect_out "^DIFFERENT: 2 differences"
    cp a/energy.csv b/
    run "$torsion" check b a --tolerance 1e-4
    expect_rc 0
    ;;

  quiet_and_verbose)
    # --quiet: nothing on stderr for a clean run, the verdict alone from check; --verbose: the
    # settings resolved. The results are the same whatever is printed.
    sed "s|../../assets/meshes|$assets|" "$scenes/twist_cylinder_2430.json" > t.json
    err=$("$torsion" run t.json --out q --steps 5 --threads 1 --quiet 2>&1 >/dev/null) ||
      fail "quiet run failed: $err"
    [[ -z $err ]] || fail "--quiet printed: $err"
    run "$torsion" --verbose run t.json --out v --steps 5 --threads 1
    expect_rc 0
    expect_out "^scene 'twist_cylinder_2430' from t.json: 5 steps of dt = 0.01 s, cg solver \(tolerance 0.0001\), 1 threads; output in v/$"
    expect_out "^done: 5 steps"
    run "$torsion" check q v --quiet
    expect_rc 0
    [[ $out == "same: q matches v within 1e-06 relative, 1e-12 absolute" ]] || fail "check --quiet: $out"
    run "$torsion" run t.json --quiet --verbose
    expect_rc 1
    ;;

  check_unreadable_directory)
    twist a
    run "$torsion" check a no_such_dir
    expect_rc 1
    expect_out "^error: no_such_dir/summary.json: cannot open"
    ;;

  check_refuses_deep_json_and_torn_rows)
    # A summary.json nested 200000 levels deep is refused before anything walks it (the walk
    # recurses), at the bracket that opens level 65; a CSV whose last row lost its newline (a
    # torn write) or some of its fields is refused with the file and the line.
    twist a
    cp -r a b
    /usr/bin/python3 -c 'print("{\"a\": " + "[" * 200000 + "]" * 200000 + "}")' > b/summary.json
    run "$torsion" check b a
    expect_rc 1
    expect_out "^error: b/summary.json:1:70: invalid JSON: nested deeper than 64 levels$"
    cp a/summary.json b/
    head -c -1 a/wrench.csv > b/wrench.csv
    run "$torsion" check b a
    expect_rc 1
    expect_out "^error: b/wrench.csv:21: the last row ends without its newline: a torn row$"
    sed '$ s/,[^,]*$//' a/wrench.csv > b/wrench.csv
    run "$torsion" check b a
    expect_rc 1
    expect_out "^error: b/wrench.csv:21: 13 values, the header has 14$"
    cp a/wrench.csv b/
    run "$torsion" check b a
    expect_rc 0
    ;;

  *)
    fail "unknown case $case_name"
    ;;
esac
echo "PASS: $case_name"
