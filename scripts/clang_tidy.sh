#!/usr/bin/env bash
# clang-tidy with the committed .clang-tidy over the library sources, extension/ and device/
# (every .cpp file there in BUILD_DIR's compile_commands.json, default build/, 2 at a time). The
# demos and tests are left out to keep this to a few minutes on 2 cores; they can be checked by
# hand with: scripts/clang_tidy.sh build demos tests
# A unity build (TORSION_UNITY_BUILD) lists its batches (BUILD_DIR/<dir>/.../Unity/unity_N_cxx.cxx)
# instead of the sources they include: those are checked, each batch parsed once, and the findings
# in the included sources reported as in any project file (HeaderFilterRegex). Only
# bugprone-suspicious-include is off for them: a batch includes .cpp files by design.
# clang-tidy looks for .clang-tidy from the checked file's directory up, and a batch lives in the
# build tree, which may be outside the repository: a batch is therefore given the root .clang-tidy
# with --config-file, and the `Checks:` line of its source directory's own .clang-tidy (each
# inherits the root's) with --checks.
# Exits non-zero on any finding.
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
shift || true
dirs=("$@")
[ ${#dirs[@]} -gt 0 ] || dirs=(extension device)
tidy=$(command -v clang-tidy-14 || command -v clang-tidy)
root=$PWD
build_abs=$(cd "$build" && pwd)
pattern=$(printf '|%s' "${dirs[@]}")
pattern="^$root/(${pattern:1})/.*\\.cpp\$|^$build_abs/(${pattern:1})/.*/Unity/unity_[0-9]+_cxx\\.cxx\$"
files=$(sed -n 's/^ *"file": "\(.*\)",\{0,1\}$/\1/p' "$build/compile_commands.json" | grep -E "$pattern" |
  sort -u)
# Longest first, so that the two workers end together: a file's cost is the size of the sources it
# compiles (a unity batch's included .cpp files). In listed order, the largest batch could start
# last and run alone.
source_bytes() {
  local file=$1
  if [[ $file == "$build_abs"/* ]]; then
    sed -n 's/^#include "\(.*\)"$/\1/p' "$file" | xargs cat | wc -c
  else
    wc -c <"$file"
  fi
}
files=$(while read -r file; do
  printf '%s %s\n' "$(source_bytes "$file")" "$file"
done <<<"$files" | sort -rn | cut -d' ' -f2-)
count=$(wc -l <<<"$files")
echo "clang-tidy: $count files (sources or unity batches) under ${dirs[*]}"

# The extra options for one file, as two arguments (empty for a source, whose directory's
# .clang-tidy clang-tidy finds itself): for a unity batch, the root config, and the checks
# bugprone-suspicious-include off plus those of the nearest .clang-tidy below the root in the source
# directory the batch was made from.
extra_options() {
  local file=$1
  if [[ $file != "$build_abs"/* ]]; then
    printf '%s\0%s\0' "" ""
    return
  fi
  local dir=$root/${file#"$build_abs"/}
  dir=${dir%%/CMakeFiles/*}
  local checks=-bugprone-suspicious-include
  while [[ $dir == "$root"/* ]]; do
    if [ -f "$dir/.clang-tidy" ]; then
      checks+=,$(sed -n "s/^Checks: *'\(.*\)'\$/\1/p" "$dir/.clang-tidy")
      break
    fi
    dir=$(dirname "$dir")
  done
  printf '%s\0%s\0' "--config-file=$root/.clang-tidy" "--checks=$checks"
}

start=$SECONDS
# clang-tidy prints "N warnings generated." for the suppressed ones (system headers): not findings.
while read -r file; do
  extra_options "$file"
  printf '%s\0' "$file"
done <<<"$files" |
  xargs -0 -P2 -n3 sh -c 'tidy=$1 build=$2 config=$3 checks=$4 file=$5
    if [ -n "$config" ]; then exec "$tidy" -p "$build" --quiet "$config" "$checks" "$file"; fi
    exec "$tidy" -p "$build" --quiet "$file"' sh "$tidy" "$build" \
    2> >(grep -v 'warnings\{0,1\} generated\.$' >&2)
echo "clang-tidy: clean ($((SECONDS - start)) s)"
