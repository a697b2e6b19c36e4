# Sourced by scripts/test.sh and scripts/main.sh: one line per stage, each stage's wall time at the
# end, and quiet configure and build steps whose errors stay visible.

stage_names=()
stage_starts=()
# stage NAME: a new stage starts now.
stage() {
  echo "== $1"
  stage_names+=("$1")
  stage_starts+=("$SECONDS")
}
# The table of stage times (wall, s); called from an EXIT trap, so a failed run shows it too.
report_stages() {
  local i end
  echo "== Stage times (wall, s)"
  for i in "${!stage_names[@]}"; do
    end=${stage_starts[$((i + 1))]:-$SECONDS}
    printf '%6d  %s\n' $((end - stage_starts[i])) "${stage_names[$i]}"
  done
  printf '%6d  total\n' "$SECONDS"
}

# configure DIR ARGS...: CMake's configure output goes to DIR/configure.log; on a failure its
# last lines are shown.
configure() {
  local dir=$1
  shift
  mkdir -p "$dir"
  if ! cmake -S . -B "$dir" -G Ninja "$@" >"$dir/configure.log" 2>&1; then
    echo "configure of $dir failed; the last lines of $dir/configure.log:" >&2
    tail -n 40 "$dir/configure.log" >&2
    return 1
  fi
}

# build DIR [ARGS...]: Ninja without its progress lines (--quiet): what is printed is a compiler's
# warning or error, and ninja's summary of a failed edge.
build() {
  local dir=$1
  shift
  cmake --build "$dir" -j"${jobs:-2}" "$@" -- --quiet
}

# seed_test_costs DIR FILE: a build tree that has never run its tests starts from the test times
# of an earlier run (FILE, CTest's own cost-file format), so that `ctest -j` starts the longest
# tests first instead of finding them in the last minute with one core idle. A tree that has run
# its tests keeps its own, newer times. Refresh FILE from a full run with
#   cp DIR/Testing/Temporary/CTestCostData.txt FILE
seed_test_costs() {
  local costs="$1/Testing/Temporary/CTestCostData.txt"
  if [ ! -s "$costs" ]; then
    mkdir -p "$(dirname "$costs")"
    cp "$2" "$costs"
  fi
}
