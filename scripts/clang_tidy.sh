#!/usr/bin/env bash
# clang-tidy with the committed .clang-tidy over the library sources, extension/ and device/
# (every .cpp file there in BUILD_DIR's compile_commands.json, default build/, 2 at a time). The
# demos and tests are left out to keep this to a few minutes on 2 cores; they can be checked by
# hand with: scripts/clang_tidy.sh build demos tests
# A unity build (TORSION_UNITY_BUILD) lists its batches (BUILD_DIR/<dir>/.../Unity/unity_N_cxx.cxx)
# instead of the sources they include: those are checked, each batch parsed once, and the findings
# in the included sources reported as in any project file (HeaderFilterRegex). Only
# bugprone-suspicious-include is off for them: a batch includes .cpp files by design.
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
extra=()
if grep -q '/Unity/unity_' <<<"$files"; then extra=(--checks=-bugprone-suspicious-include); fi
count=$(wc -l <<<"$files")
echo "clang-tidy: $count files (sources or unity batches) under ${dirs[*]}"
start=$SECONDS
# clang-tidy prints "N warnings generated." for the suppressed ones (system headers): not findings.
xargs -P2 -n4 "$tidy" -p "$build" --quiet "${extra[@]}" <<<"$files" 2> >(grep -v 'warnings\{0,1\} generated\.$' >&2)
echo "clang-tidy: clean ($((SECONDS - start)) s)"
