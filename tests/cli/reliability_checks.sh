#!/usr/bin/env bash
# The torsion tool losing nothing and reporting nothing false: bad input is a clear error,
# outputs are complete or absent, signals stop a run cleanly (docs/outputs.md).
#   reliability_checks.sh CASE TORSION ASSETS_DIR FAIL_WRITES_SHIM [HAPTIC_PEER]
# Exit 0: pass; 77: skipped (the reason is printed); anything else: fail.
set -uo pipefail

case_name=$1
torsion=$2
assets=$3
shim=${4:-}
peer=${5:-}
scenes=$(cd "$(dirname "$0")/../../demos/scenes" && pwd)

work_name=torsion-reliability
source "$(dirname "$0")/case_helpers.sh"

expect_rc() {  # expect_rc N
  [[ $rc -eq $1 ]] || fail "exit code $rc, expected $1"
}
# json_field FILE KEY: a top-level value of a JSON file, as Python prints it.
json_field() {
  python3 -c 'import json, sys; print(json.load(open(sys.argv[1])).get(sys.argv[2]))' "$1" "$2"
}
no_temporaries() {  # no_temporaries DIR: nothing half-written is left behind
  local left
  left=$(find "$1" -name '*.tmp-*' -o -name '*.partial' -o -name '*.old-*')
  [[ -z $left ]] || fail "temporary files left: $left"
}
# Every row of a CSV has as many fields as its header.
csv_rows_whole() {
  awk -F, 'NR == 1 { n = NF } NF != n { bad = 1 } END { exit bad }' "$1" ||
    fail "$1 has a torn row"
}

drop_scene() {  # the drop scene with its mesh path made absolute; extra sed expressions allowed
  sed -e "s|../../assets/meshes|$assets|" "$@" "$scenes/drop.json"
}
twist_scene() {
  sed -e "s|../../assets/meshes|$assets|" "$@" "$scenes/twist_cylinder_2430.json"
}

# start_run OUT ARGS...: torsion run in the background (pid in $sim), log in run.log. SIGINT is
# given back its default first: a non-interactive shell starts background jobs ignoring it, and
# torsion keeps a signal ignored that it was started ignoring.
start_run() {
  local dir=$1
  shift
  env --default-signal=INT "$torsion" run "$@" --out "$dir" >run.log 2>&1 &
  sim=$!
}

# A twist run whose hand the reference network peer holds (peer_pid), returning once the peer
# renders a non-zero torque (up to 30 s: slow under sanitizers). Whole rows only: the peer's log
# is being written, and its last line may be cut inside a number ("-1.2e-05" read as "-1.2"
# looked like a held torque).
peer_holds_the_hand() {
  [[ -x $peer ]] || fail "no torsion_haptic_peer given"
  twist_scene > twist.json
  cat > hold.json <<'JSON'
{"segments": [{"duration": 0.6, "angular_velocity": [0, 0, 0.5]}, {"duration": 60}],
 "buttons": [{"time": 0, "held": [1]}]}
JSON
  port=$((20000 + RANDOM % 20000))
  start_run out twist.json --device "hand=network:$port" --steps 100000 --threads 1
  wait_for_network_device run.log
  "$peer" --trajectory hold.json --port "$port" --log peer.csv >peer.log 2>&1 &
  peer_pid=$!
  for _ in $(seq 300); do
    head -n -1 peer.csv 2>/dev/null |
      awk -F, 'NR > 1 && NF == 8 && ($7 > 0.1 || $7 < -0.1) { found = 1 } END { exit !found }' &&
      break
    sleep 0.1
  done
}

# wait_rows FILE N: waits (up to 20 s) until FILE has at least N lines.
wait_rows() {
  for _ in $(seq 200); do
    [[ -f $1 && $(wc -l <"$1") -ge $2 ]] && return 0
    sleep 0.1
  done
  kill -9 "$sim" 2>/dev/null
  fail "$1 never reached $2 lines"
}

# stop_with SIGNAL EXPECTED_RC: a run stopped by the signal after some steps keeps whole outputs.
stop_with() {
  local signal=$1 expected=$2
  twist_scene > twist.json
  write_short_turn turn.json
  start_run out twist.json --steps 100000 --threads 1 --device hand=scripted:turn.json
  wait_rows out/wrench.csv 6
  kill "-$signal" "$sim"
  wait "$sim"
  rc=$?
  out=$(cat run.log)
  printf '%s\n' "$out"
  expect_rc "$expected"
  expect_out "^stopped by SIG$signal after [0-9]+ steps"
  [[ $(json_field out/summary.json completed) == False ]] || fail "summary says completed"
  [[ $(json_field out/summary.json stopped_by) == "SIG$signal" ]] || fail "summary lacks stopped_by"
  local steps rows
  steps=$(json_field out/summary.json steps)
  rows=$(($(wc -l <out/wrench.csv) - 1))
  [[ $steps -ge 5 && $steps -eq $rows ]] || fail "summary says $steps steps, wrench.csv has $rows"
  [[ $(($(wc -l <out/energy.csv) - 1)) -eq $steps ]] || fail "energy.csv does not match the steps"
  csv_rows_whole out/wrench.csv
  "$torsion" mesh info out/cylinder.vtk >/dev/null || fail "the final mesh does not read back"
  [[ -s out/haptic_hand.csv ]] || fail "the haptic log was not written"
  no_temporaries out
}

# with_full_disk PATTERN AFTER CMD...: runs CMD with writes to files matching PATTERN failing
# with ENOSPC after AFTER bytes (fail_writes_shim.c).
with_full_disk() {
  local pattern=$1 after=$2
  shift 2
  [[ -f $shim ]] || skip "the write-failure shim was not built"
  rm -f shim.mark
  out=$(TORSION_FAIL_WRITES_TO="$pattern" TORSION_FAIL_WRITES_AFTER="$after" \
        TORSION_FAIL_WRITES_MARK="$work/shim.mark" LD_PRELOAD="$shim" \
        ASAN_OPTIONS="${ASAN_OPTIONS:-}:verify_asan_link_order=0" "$@" 2>&1)
  rc=$?
  printf '%s\n' "$out"
  [[ -f shim.mark ]] || skip "LD_PRELOAD of the write-failure shim did not take (sanitizer build?)"
}

case "$case_name" in
  json_number_overflow)
    # 1e400 does not fit a double: an error with its position, not an abort.
    drop_scene -e 's/"steps": 150/"steps": 1e400/' > big.json
    run "$torsion" run big.json --out out
    expect_rc 1
    expect_out "^error: big.json:3:[0-9]+: invalid JSON: number out of range of a double: 1e400$"
    [[ ! -e out ]] || fail "nothing may be written for a bad scene"
    ;;
  json_duplicate_key)
    # The last of two equal keys used to win silently; now both the top level and a nested
    # object name the key.
    drop_scene -e 's/"steps": 150,/"steps": 150, "steps": 3,/' > top.json
    run "$torsion" run top.json --out out
    expect_rc 1
    expect_out "^error: top.json: invalid JSON: duplicate key 'steps' in the top-level object$"
    drop_scene -e 's/"density": 500,/"density": 500, "density": 5,/' > nested.json
    run "$torsion" run nested.json --out out
    expect_rc 1
    expect_out "duplicate key 'density' in object 'bodies\[0\].material'$"
    [[ ! -e out ]] || fail "nothing may be written for a bad scene"
    ;;
  mesh_path_too_long)
    # A path without extension probes "<path>.node"; too long a name is an error, not an abort.
    long=$(printf 'a%.0s' $(seq 5000))
    run "$torsion" mesh info "$long"
    expect_rc 1
    expect_out "^error: a+: unknown mesh format"
    ;;
  scene_name_not_utf8)
    # A scene file named in another encoding: the run completes and summary.json is valid JSON.
    drop_scene -e '/"name": "drop"/d' > $'drop\xff.json'
    run "$torsion" run $'drop\xff.json' --out out --steps 3
    expect_rc 0
    [[ $(json_field out/summary.json completed) == True ]] || fail "summary.json is not complete"
    [[ -s out/ball.vtk && -s out/wrench.csv ]] || fail "outputs missing"
    ;;
  summary_is_directory)
    # summary.json cannot be replaced: an error naming it and the reason, exit 1.
    drop_scene > drop.json
    mkdir -p out/summary.json/inside
    run "$torsion" run drop.json --out out --steps 3
    expect_rc 1
    expect_out "^error: out/summary.json: cannot write: is a directory, not a regular file$"
    no_temporaries out
    ;;
  full_disk_csv)
    # The disk fills up while wrench.csv grows: the error names the file and the reason, the
    # summary says the run did not complete, and every row on disk is whole.
    drop_scene > drop.json
    with_full_disk wrench.csv 300 "$torsion" run drop.json --out out --steps 100
    expect_rc 1
    expect_out "^error: out/wrench.csv: write failed: No space left on device$"
    [[ $(json_field out/summary.json completed) == False ]] || fail "summary says completed"
    json_field out/summary.json error | grep -q "wrench.csv: write failed" ||
      fail "summary.json does not record the error"
    csv_rows_whole out/wrench.csv
    no_temporaries out
    ;;
  full_disk_mesh)
    # The final mesh cannot be written: no ball.vtk at all rather than a torn one.
    drop_scene > drop.json
    with_full_disk ball.vtk 4096 "$torsion" run drop.json --out out --steps 5
    expect_rc 1
    expect_out "^error: out/ball.vtk: cannot write: No space left on device$"
    [[ ! -e out/ball.vtk ]] || fail "a torn ball.vtk was left"
    [[ $(json_field out/summary.json completed) == False ]] || fail "summary says completed"
    no_temporaries out
    ;;
  convert_tetgen_pair_together)
    # The .ele cannot be replaced (a directory is in the way): the .node keeps its old content.
    "$torsion" mesh box --min 0 0 0 --max 1 1 1 --cells 1 1 1 -o box.vtk >/dev/null ||
      fail "mesh box failed"
    printf 'old\n' > out.node
    mkdir out.ele
    run "$torsion" mesh convert box.vtk out.node
    expect_rc 1
    expect_out "^error: out.ele: cannot write: is a directory, not a regular file$"
    [[ $(cat out.node) == old ]] || fail "out.node was replaced without its .ele"
    no_temporaries .
    ;;
  new_run_replaces_earlier)
    # A second run into the same --out leaves none of the first run's files behind.
    twist_scene > twist.json
    drop_scene > drop.json
    run "$torsion" run twist.json --out out --steps 2 --threads 1
    expect_rc 0
    [[ -s out/cylinder.vtk ]] || fail "first run: no cylinder.vtk"
    run "$torsion" run drop.json --out out --steps 2
    expect_rc 0
    [[ ! -e out/cylinder.vtk ]] || fail "the earlier run's cylinder.vtk is still there"
    [[ -s out/ball.vtk ]] || fail "second run: no ball.vtk"
    head -1 out/wrench.csv | grep -q hand && fail "wrench.csv still has the earlier run's columns"
    python3 -c 'import json; assert json.load(open("out/summary.json"))["outputs"] == ["wrench.csv", "energy.csv", "ball.vtk"]' ||
      fail "summary.json does not list this run's outputs"
    ;;
  sigint_stops_at_a_step)
    stop_with INT 130
    ;;
  sigterm_stops_at_a_step)
    stop_with TERM 143
    ;;
  sighup_stops_at_a_step)
    # The terminal or ssh session that started the run closed: stopped as by SIGTERM.
    stop_with HUP 129
    ;;
  sigkill_leaves_whole_rows)
    # After SIGKILL nothing is finished, but what is on disk parses and says so.
    twist_scene > twist.json
    start_run out twist.json --steps 100000 --threads 1
    wait_rows out/wrench.csv 20
    kill -9 "$sim"
    wait "$sim"
    [[ $(json_field out/summary.json completed) == False ]] || fail "summary says completed"
    csv_rows_whole out/wrench.csv
    csv_rows_whole out/energy.csv
    [[ ! -e out/cylinder.vtk ]] || fail "a final mesh exists for a run that never finished"
    ;;
  refuse_overflowing_values)
    # Values the arithmetic cannot carry used to run as "stable" with CG at 0 iterations and
    # residual 0, or fill rigid.csv with nan: now refused at load, naming the bound.
    drop_scene -e 's/"steps": 150,/"steps": 20, "gravity": [0, 0, -1e160],/' > gravity.json
    run "$torsion" run gravity.json --out out
    expect_rc 1
    expect_out "^error: gravity.json: gravity: magnitude 1e\+160 m/s\^2 is above the bound 1e\+06 m/s\^2"
    twist_scene -e 's/"youngs_modulus": [0-9.e+]*/"youngs_modulus": 1e300/' > stiff.json
    run "$torsion" run stiff.json --out out --steps 5
    expect_rc 1
    expect_out "^error: stiff.json: bodies\[0\] 'cylinder': material: E dt\^2 / \(rho h\^2\) = .* is above the bound 1e\+100"
    sed -e "s|../../assets/meshes|$assets|" -e 's/"radius": 0.15/"radius": 1e300/' \
      "$scenes/rigid_mix.json" > sphere.json
    run "$torsion" run sphere.json --out out --steps 5
    expect_rc 1
    expect_out "^error: sphere.json: rigid_bodies\[1\].shape.sphere.radius: must be at most 1e6 m"
    sed -e "s|../../assets/meshes|$assets|" \
      -e 's/"convex_hull": {"points"/"convex_hull": {"margin": 1e300, "points"/' \
      "$scenes/rigid_mix.json" > hull.json
    run "$torsion" run hull.json --out out --steps 5
    expect_rc 1
    expect_out "shape.convex_hull.margin: must be at most 1e6 m"
    [[ ! -e out ]] || fail "nothing may be written for a refused scene"
    ;;
  names_checked_at_load)
    # Names become file names (<body>.vtk) and CSV columns: nothing may leave --out or clash.
    drop_scene -e 's|"name": "ball"|"name": "../escape"|' > slash.json
    run "$torsion" run slash.json --out out
    expect_rc 1
    expect_out "^error: slash.json: bodies\[0\].name: character '/' not allowed"
    [[ ! -e escape.vtk ]] || fail "a file was written outside --out"
    drop_scene -e 's|"name": "ball"|"name": ""|' > empty.json
    run "$torsion" run empty.json --out out
    expect_rc 1
    expect_out "^error: empty.json: bodies\[0\].name: must not be empty$"
    drop_scene -e 's|"name": "ball"|"name": "a,b"|' > comma.json
    run "$torsion" run comma.json --out out
    expect_rc 1
    expect_out "character ',' not allowed"
    twist_scene -e 's|"name": "base", "body"|"name": "hand", "body"|' > clash.json
    grep -q '"name": "hand", "body"' clash.json || fail "test setup: no node set renamed"
    run "$torsion" run clash.json --out out
    expect_rc 1
    expect_out "^error: clash.json: hands\[0\].name: 'hand' is also a node set's name: both would be columns of wrench.csv$"
    [[ ! -e out ]] || fail "nothing may be written for a refused scene"
    ;;
  only_regular_files_read)
    # A FIFO used to block forever and /dev/zero to be read until memory ran out.
    mkfifo mesh.vtk
    run timeout 10 "$torsion" mesh info mesh.vtk
    expect_rc 1
    expect_out "^error: mesh.vtk: cannot open: is a FIFO, not a regular file$"
    ln -s /dev/zero zero.vtk
    run timeout 10 "$torsion" mesh info zero.vtk
    expect_rc 1
    expect_out "^error: zero.vtk: cannot open: is a character device, not a regular file$"
    printf 'x%.0s' $(seq 3000) > big.vtk
    run "$torsion" mesh info big.vtk --max-input-mb 0.001
    expect_rc 1
    expect_out "^error: big.vtk: 3000 bytes, above the input size cap of 1000 bytes \(raise it with --max-input-mb\)$"
    ;;
  errors_show_no_raw_bytes)
    # A file name with a byte that is not UTF-8 is shown escaped, not sent raw to the terminal.
    run "$torsion" run $'nope\xff\x1b[2J.json' --out out
    expect_rc 1
    expect_out '^error: nope\\xFF\\x1B\[2J.json: no such scene file'
    LC_ALL=C grep -q $'\xff' <<<"$out" && fail "a raw 0xFF byte reached stderr"
    [[ $out == *$'\x1b'* ]] && fail "a raw escape character reached stderr"
    # Valid UTF-8 stays as it is.
    run "$torsion" run 'nöpe.json' --out out
    expect_out "^error: nöpe.json: no such scene file"
    ;;
  threads_reported_as_used)
    # More threads than cores run on the cores: the summary reports the count used (TBB's core
    # count, which honours the affinity mask like nproc; a CPU quota may lower it further).
    cores=$(nproc)
    asked=$((cores + 7))
    drop_scene > drop.json
    run "$torsion" run drop.json --out out --steps 2 --threads $asked
    expect_rc 0
    expect_out "^warning: $asked threads asked for, the machine has [0-9]+ cores: using [0-9]+$"
    used=$(sed -n 's/^warning: .* using \([0-9]*\)$/\1/p' <<<"$out")
    [[ $used -ge 1 && $used -le $cores ]] || fail "using $used threads on $cores cores"
    [[ $(json_field out/summary.json threads) == "$used" ]] || fail "summary does not report $used threads"
    # 0 is every core unless TORSION_THREADS says otherwise (a test run sets it to 1).
    TORSION_THREADS= run "$torsion" run drop.json --out out --steps 2 --threads 0
    [[ $(json_field out/summary.json threads) == "$used" ]] || fail "--threads 0 is not all $used cores"
    TORSION_THREADS=1 run "$torsion" run drop.json --out out --steps 2 --threads 0
    [[ $(json_field out/summary.json threads) == 1 ]] || fail "TORSION_THREADS=1 is not 1 thread"
    TORSION_THREADS=1 run "$torsion" run drop.json --out out --steps 2 --threads $cores
    [[ $(json_field out/summary.json threads) == "$cores" ]] || fail "--threads lost to TORSION_THREADS"
    TORSION_THREADS=two run "$torsion" run drop.json --out out --steps 2
    expect_rc 1
    expect_out "^error: TORSION_THREADS='two' is not a whole number of threads from 1 to 4096"
    ;;
  huge_step_count_reserves_nothing)
    # --steps 2e9 used to reserve 16 GB of step timings up front; memory now grows with the steps
    # done. Peak virtual size after a few steps stays far below (1 GB; a run of the drop scene
    # needs ~50 MB).
    # Measured against the same run asked for 1000 steps, so a sanitizer's own reservations
    # (ASan maps terabytes of shadow memory) cancel out.
    drop_scene > drop.json
    start_run small drop.json --steps 1000
    wait_rows small/wrench.csv 5
    base_kb=$(sed -n 's/^VmPeak:[[:space:]]*\([0-9]*\) kB/\1/p' "/proc/$sim/status")
    kill -INT "$sim"
    wait "$sim"
    start_run out drop.json --steps 2000000000
    wait_rows out/wrench.csv 5
    peak_kb=$(sed -n 's/^VmPeak:[[:space:]]*\([0-9]*\) kB/\1/p' "/proc/$sim/status")
    kill -INT "$sim"
    wait "$sim"
    rc=$?
    expect_rc 130
    [[ -n $base_kb && -n $peak_kb && $((peak_kb - base_kb)) -lt 1000000 ]] ||
      fail "peak virtual size ${peak_kb} kB against ${base_kb} kB for 1000 steps"
    [[ $(json_field out/summary.json steps_requested) == 2000000000 ]] || fail "steps_requested"
    ;;
  remote_device_needs_a_flag)
    # Listening outside loopback lets any host drive the hand: an explicit flag, and a warning.
    twist_scene > twist.json
    run "$torsion" run twist.json --device hand=network:0.0.0.0:0 --out out --steps 1
    expect_rc 1
    expect_out "^error: twist.json: hands\[0\] 'hand': device host 0.0.0.0 is not loopback: .* pass --allow-remote-device"
    [[ ! -e out ]] || fail "nothing may be written for a refused device"
    run "$torsion" run twist.json --device hand=network:0.0.0.0:0 --allow-remote-device \
      --out out --steps 1 --threads 1
    expect_rc 0
    expect_out "^warning: hand 'hand': the network device listens on 0.0.0.0, outside loopback"
    ;;

  sigkill_fades_the_network_peer)
    # torsion killed while a peer is holding the hand: nothing more is sent, and the peer's
    # watchdog fades the wrench it renders to zero (0.1 s without a wrench, then at most 0.2 s),
    # down through values in between, never holding the last one.
    peer_holds_the_hand
    kill -KILL "$sim"
    wait "$sim"
    rc=$?
    sleep 0.6  # the peer goes on ticking: past the timeout and the fade
    kill -TERM "$peer_pid" 2>/dev/null
    wait "$peer_pid"
    cat peer.log
    expect_rc 137
    tail -1 peer.csv | awk -F, '{ for (i = 2; i <= 7; i++) if ($i != 0) exit 1 }' ||
      fail "the peer still renders a wrench: $(tail -1 peer.csv)"
    # The torque about z after the last row of the held torque: falls through values in between.
    awk -F, 'NR > 1 { t = $7 < 0 ? -$7 : $7; if (t > 0.1) { held = t; n = 0 } else if (held > 0 && t > 0) n++ }
      END { exit !(held > 0 && n > 0) }' peer.csv ||
      fail "the peer's torque did not fade (a cut or a hold)"
    ;;
  sigint_zeroes_the_network_device)
    # Ctrl-C while a peer is holding the hand: the run stops marked, and the last wrench the peer
    # receives is zero (the loop's stop and the device's close each send one).
    peer_holds_the_hand
    kill -INT "$sim"
    wait "$sim"
    rc=$?
    sleep 0.3  # the peer goes on ticking: its log's last rows come after the close
    kill -TERM "$peer_pid" 2>/dev/null  # the peer stops cleanly: its log ends with a whole row
    wait "$peer_pid"
    cat run.log peer.log
    expect_rc 130
    [[ $(json_field out/summary.json stopped_by) == SIGINT ]] || fail "summary lacks stopped_by"
    awk -F, 'NR > 1 && ($7 > 0.1 || $7 < -0.1) { found = 1 } END { exit !found }' peer.csv ||
      fail "the peer never held a torque"
    tail -1 peer.csv | awk -F, '{ for (i = 2; i <= 7; i++) if ($i != 0) exit 1 }' ||
      fail "the peer's last wrench is not zero: $(tail -1 peer.csv)"
    ;;

  network_device_key)
    # A shared key (docs/haptic-devices.md, "Authentication"): the signed peer drives the hand
    # while an unsigned one, sending to the same port at the same time, is refused and counted.
    [[ -x $peer ]] || fail "no torsion_haptic_peer given"
    twist_scene > twist.json
    cat > turn.json <<'JSON'
{"segments": [{"duration": 0.6, "angular_velocity": [0, 0, 0.5]}, {"duration": 0.2}],
 "buttons": [{"time": 0, "held": [1]}]}
JSON
    (umask 077 && head -c 32 /dev/urandom | od -An -tx1 | tr -d ' \n' > haptic.key)
    port=$((20000 + RANDOM % 20000))
    TORSION_HAPTIC_KEY_FILE=haptic.key "$torsion" run twist.json --device "hand=network:$port" \
      --out net --steps 150 --threads 1 >torsion.log 2>&1 &
    sim=$!
    wait_for_network_device torsion.log
    grep -q "device network(udp port $port)" torsion.log ||
      { kill "$sim"; cat torsion.log; fail "torsion did not open the network device"; }
    "$peer" --trajectory turn.json --port "$port" --rate 500 >hostile.log 2>&1 &
    hostile=$!
    "$peer" --trajectory turn.json --port "$port" --key-file haptic.key >peer.log 2>&1 ||
      { cat peer.log; fail "the signed peer failed"; }
    wait "$hostile"
    wait "$sim"
    rc=$?
    cat torsion.log peer.log hostile.log
    expect_rc 0
    grep -q "signed with the shared key" peer.log || fail "the peer did not sign"
    python3 - net/summary.json <<'PY' || fail "packet counts"
import json, sys
p = json.load(open(sys.argv[1]))["haptics"][0]["packets"]
print(p)
assert p["authenticated"] is True, p
assert p["accepted"] >= 100, p          # the signed peer drove the hand
assert p["unauthenticated"] >= 100, p   # the unsigned peer was heard and refused
assert p["foreign"] == 0 and p["replayed"] == 0, p
PY
    grep -q "rejected 0" peer.log || fail "the signed peer rejected wrenches"
    grep -Eq "accepted 0 wrenches" hostile.log || fail "the unsigned peer received a wrench"

    # Bad keys are clear errors before anything runs; a key is never a command-line argument.
    printf 'short\n' > short.key && chmod 600 short.key
    run env TORSION_HAPTIC_KEY_FILE=short.key "$torsion" run twist.json \
      --device hand=network:0 --out bad --steps 1
    expect_rc 1
    expect_out "^error: .*key file short.key: the key has 5 bytes, fewer than the 32 required"
    run env TORSION_HAPTIC_KEY_FILE=missing.key "$torsion" run twist.json \
      --device hand=network:0 --out bad --steps 1
    expect_rc 1
    expect_out "^error: .*key file missing.key: cannot open: No such file or directory"
    cp haptic.key shared.key && chmod 644 shared.key
    run "$peer" --trajectory turn.json --port 9 --key-file shared.key
    expect_rc 1
    expect_out "^error: key file shared.key: other users can access it; restrict it with chmod 600$"
    run "$peer" --trajectory turn.json --port 9 --key "$(cat haptic.key)"
    expect_rc 1
    expect_out "^error: --key: a key on the command line is visible to every local user"
    [[ ! -e bad ]] || fail "nothing may be written when the key cannot be read"
    ;;
  outputs_replace_only_regular_files)
    # A file written whole is renamed over its name, which would make a FIFO, a device or a
    # symbolic link a regular file: those are refused, named with their kind, and left as they are.
    drop_scene > drop.json
    mkdir fifo link series
    mkfifo fifo/summary.json
    run "$torsion" run drop.json --out fifo --steps 3
    expect_rc 1
    expect_out "^error: fifo/summary.json: cannot write: is a FIFO, not a regular file$"
    [[ -p fifo/summary.json ]] || fail "the FIFO was replaced"
    no_temporaries fifo
    printf 'kept\n' > target.json
    ln -s ../target.json link/summary.json
    run "$torsion" run drop.json --out link --steps 3
    expect_rc 1
    expect_out "^error: link/summary.json: cannot write: is a symbolic link, not a regular file$"
    [[ -L link/summary.json && $(cat target.json) == kept ]] || fail "the link or its target changed"
    no_temporaries link
    # At a name the run writes, a FIFO or a link is not removed to make room: the same error.
    mkdir csv
    mkfifo csv/wrench.csv
    run "$torsion" run drop.json --out csv --steps 3
    expect_rc 1
    expect_out "^error: csv/wrench.csv: cannot write: is a FIFO, not a regular file$"
    [[ -p csv/wrench.csv ]] || fail "the FIFO at wrench.csv was replaced"
    rm csv/wrench.csv
    ln -s ../target.json csv/ball.vtk
    run "$torsion" run drop.json --out csv --steps 3
    expect_rc 1
    expect_out "^error: csv/ball.vtk: cannot write: is a symbolic link, not a regular file$"
    [[ -L csv/ball.vtk && $(cat target.json) == kept ]] || fail "the link at ball.vtk changed"
    # A FIFO among the series' files (only regular .vtu files are cleared when a series starts).
    mkdir series/series
    mkfifo series/series/ball_000000.vtu
    run "$torsion" run drop.json --out series --steps 3 --vtk-every 1
    expect_rc 1
    expect_out "^error: --vtk-every: series/series/ball_000000.vtu: cannot write: is a FIFO, not a regular file$"
    [[ -p series/series/ball_000000.vtu ]] || fail "the series FIFO was replaced"
    # torsion mesh writes its output the same way.
    "$torsion" mesh box --min 0 0 0 --max 1 1 1 --cells 1 1 1 -o box.vtk >/dev/null ||
      fail "mesh box failed"
    ln -s target.json linked.vtk
    run "$torsion" mesh convert box.vtk linked.vtk
    expect_rc 1
    expect_out "^error: linked.vtk: cannot write: is a symbolic link, not a regular file$"
    [[ -L linked.vtk && $(cat target.json) == kept ]] || fail "mesh convert replaced the link"
    no_temporaries .
    ;;
  step_output_error_is_no_completed_run)
    # A series step that cannot be written stops the run as an output error: exit 1, and the
    # summary says the run did not complete, with the error.
    drop_scene > drop.json
    with_full_disk _000002.vtu 0 "$torsion" run drop.json --out out --steps 5 --vtk-every 1
    expect_rc 1
    expect_out "^error: --vtk-every: out/series/ball_000002.vtu: cannot write: No space left on device$"
    [[ $(json_field out/summary.json completed) == False ]] || fail "summary says completed"
    json_field out/summary.json error | grep -q "out/series/ball_000002.vtu: cannot write" ||
      fail "summary.json lacks the error"
    [[ $(json_field out/summary.json steps) -eq 2 ]] || fail "the run did not stop at step 2"
    csv_rows_whole out/wrench.csv
    no_temporaries out
    ;;
  render_error_is_no_completed_run)
    # The same for a --render picture that cannot be written (a directory holds its name).
    drop_scene > drop.json
    "$torsion" run drop.json --out probe --steps 1 --render probe_pictures --render-size 64x48 \
      >/dev/null 2>&1 || skip "no offscreen rendering (OSMesa) here"
    mkdir -p pictures/frame_00002.png
    run "$torsion" run drop.json --out out --steps 4 --render pictures --render-every 1 \
      --render-size 64x48
    expect_rc 1
    expect_out "^error: --render: pictures/frame_00002.png: cannot write: is a directory, not a regular file$"
    [[ $(json_field out/summary.json completed) == False ]] || fail "summary says completed"
    json_field out/summary.json error | grep -q "pictures/frame_00002.png" ||
      fail "summary.json lacks the error"
    [[ $(json_field out/summary.json steps) -eq 2 ]] || fail "the run did not stop at step 2"
    no_temporaries out
    ;;
  series_names_do_not_collide)
    # A series names a FEM body's files "<name>_<step>.vtu" and a rigid body's
    # "rigid_<name>_<step>.vtu": FEM body "rigid_X" beside rigid body "X" is refused before any
    # step, for a rigid body of the scene and for one a .bullet file brings (named by the file).
    drop_scene -e 's/"name": "ball"/"name": "rigid_floor"/; s/"body": "ball"/"body": "rigid_floor"/g' \
      -e 's/"ground": {/"rigid_bodies": [{"name": "floor", "shape": {"sphere": {"radius": 0.1}}, "pose": {"position": [5, 5, 5]}, "mass": 0}], "ground": {/' > drop.json
    grep -q '"floor"' drop.json || fail "the scene with a rigid body was not made"
    run "$torsion" run drop.json --out out --steps 2
    expect_rc 1
    expect_out "^error: drop.json: rigid_bodies\[0\].name: rigid body 'floor' and FEM body 'rigid_floor' would write the same series files \(series/rigid_floor_<step>.vtu\): rename one$"
    [[ ! -e out ]] || fail "nothing may be written for a bad scene"
    sed -e "s|../../assets/meshes|$assets|; s|../../assets/bullet|$assets/../bullet|" \
      -e 's/"slab"/"rigid_boxes_1"/g' "$scenes/bullet_boxes.json" > boxes.json
    run "$torsion" run boxes.json --out out --steps 2
    expect_rc 1
    expect_out "^error: boxes.json: bullet_file: .*/boxes.bullet: rigid_bodies\[1\].name: rigid body 'boxes_1' and FEM body 'rigid_boxes_1' would write the same series files"
    [[ ! -e out ]] || fail "nothing may be written for a bad scene"
    ;;
  stale_temporaries_removed)
    # A killed run leaves the temporaries of its atomic writes; the next run into the directory
    # removes those of its own file names whose process is gone, and nothing else.
    drop_scene > drop.json
    mkdir -p out/series
    dead=99999999  # above any pid_max: no such process
    for f in summary.json ball.vtk series.pvd; do
      echo torn > "out/$f.tmp-$dead"
    done
    echo torn > "out/ball.vtk.old-$dead"
    echo torn > "out/series/ball_000010.vtu.tmp-$dead"
    echo mine > "out/notes.txt.tmp-$dead"      # not a name of the run
    echo mine > "out/ball.vtk.tmp-$$"          # its process (this shell) still runs
    echo mine > "out/ball.vtk.tmp-backup"      # not a process id
    run "$torsion" run drop.json --out out --steps 3 --vtk-every 1
    expect_rc 0
    left=$(cd out && find . -name '*.tmp-*' -o -name '*.old-*' | LC_ALL=C sort | tr '\n' ' ')
    [[ $left == "./ball.vtk.tmp-$$ ./ball.vtk.tmp-backup ./notes.txt.tmp-$dead " ]] ||
      fail "left behind: $left"
    ;;
  *)
    fail "unknown case '$case_name'"
    ;;
esac
echo "PASS: $case_name"
