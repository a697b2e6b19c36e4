# Sourced by the CLI check scripts (cli_checks.sh, reliability_checks.sh, check_checks.sh,
# mesh_checks.sh), each of which runs one case per call: the case's fresh temporary working
# directory, removed on exit, and the helpers their cases share. Set work_name (the directory's
# name prefix) before sourcing.
# shellcheck shell=bash

work=$(mktemp -d "${TMPDIR:-/tmp}/$work_name-XXXXXX")
trap 'rm -rf "$work"' EXIT
cd "$work" || exit 1

# fail MESSAGE: the case fails (exit 1), MESSAGE on stderr.
fail() {
  echo "FAIL: $*" >&2
  exit 1
}

# skip REASON: the case is skipped (exit 77, the tests' SKIP_RETURN_CODE).
skip() {
  echo "SKIP: $*"
  exit 77
}

# run CMD...: runs it, keeping its exit code in $rc and its stdout+stderr in $out (and printing it).
run() {
  out=$("$@" 2>&1)
  rc=$?
  printf '%s\n' "$out"
}

# expect_out REGEX: some line of the last run's output matches REGEX (extended).
expect_out() {
  grep -Eq -- "$1" <<<"$out" || fail "output does not match: $1"
}

# write_short_turn FILE: a short device trajectory: button 1 at 0 s grabs, a turn about z at
# 0.5 rad/s for 0.6 s, a hold, button 2 at 0.8 s releases; the peer holds the end for 0.5 s more.
write_short_turn() {
  cat >"$1" <<'JSON'
{"segments": [{"duration": 0.6, "angular_velocity": [0, 0, 0.5]}, {"duration": 0.4}],
 "buttons": [{"time": 0, "held": [1]}, {"time": 0.8, "held": [2]}]}
JSON
}

# wait_for_network_device LOG: waits (up to 10 s) until the run writing LOG says it opened its
# network device, so that a peer started next finds the port bound.
wait_for_network_device() {
  for _ in $(seq 100); do
    grep -q "device network" "$1" && return
    sleep 0.1
  done
}
