#!/usr/bin/env bash
# The whole test suite, from a fresh machine: set-up, Release build, every CTest test, clang-tidy
# over the libraries, the fast tests again on float Bullet, then a clang build with ASan+UBSan
# that runs the unit tests again and fuzzes each mesh reader for a bounded time. `.ci/run` calls
# exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)

# Each stage's wall time, printed at the end whether the run passes or fails, so a slow CI run
# shows where its minutes went.
stage_names=()
stage_starts=()
stage() {
  echo "== $1"
  stage_names+=("$1")
  stage_starts+=("$SECONDS")
}
report_stages() {
  local rc=$? i end
  echo "== Stage times (wall, s)"
  for i in "${!stage_names[@]}"; do
    end=${stage_starts[$((i + 1))]:-$SECONDS}
    printf '%6d  %s\n' $((end - stage_starts[i])) "${stage_names[$i]}"
  done
  printf '%6d  total\n' "$SECONDS"
  return "$rc"
}
trap report_stages EXIT
# Every build here starts clean, so the libraries, the tool and the Python module compile as
# unity batches (TORSION_UNITY_BUILD: half the minutes on 2 cores).
# The extra builds compile only what their fast labels run (no physics, regression or render
# executables, no Python module, no benchmarks); the sanitizers keep line tables, not full debug
# information, which is enough for their reports.
unity=(-DTORSION_UNITY_BUILD=ON)
fast_only=("${unity[@]}" -DTORSION_BUILD_SLOW_TESTS=OFF -DTORSION_PYTHON=OFF -DTORSION_BUILD_BENCHMARKS=OFF)
sanitizer_flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++
  "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG")

stage "Set-up (scripts/setup.sh)"
bash scripts/setup.sh

stage "Release build (build/)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTORSION_WARNINGS_AS_ERRORS=ON "${unity[@]}"
cmake --build build -j"$jobs"
stage "Test suite"
ctest --test-dir build -j"$jobs" --output-on-failure --timeout 900
# The pytest suite is one CTest test (python.pytest); its own count of tests:
grep -hEo "^[0-9]+ passed.* in [0-9.]+s" build/Testing/Temporary/LastTest.log | tail -1 |
  sed 's/^/== pytest (label python): /' || true
stage "clang-tidy (.clang-tidy) over extension/ and device/, from build/compile_commands.json"
bash scripts/clang_tidy.sh build

stage "ThreadSanitizer build (build-tsan/, clang): the haptic loop's thread, its buffers, the runtime"
cmake -S . -B build-tsan -G Ninja "${sanitizer_flags[@]}" "${fast_only[@]}" -DTORSION_TSAN=ON \
  -DTORSION_BUILD_DEMOS=OFF
cmake --build build-tsan -j"$jobs" --target torsion_device_tests torsion_bullet_tests
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest --test-dir build-tsan -j"$jobs" --output-on-failure --timeout 900 \
  -R "HapticLoop|TripleBuffer|NetworkDevice|PluginDevice|UserWorldHaptics"

stage "Float-Bullet build (build-float/): Debian's default Bullet; fast tests and the package"
# The same code on pkg-config `bullet` (btScalar = float), the Bullet most programs link. The
# package test also installs build/ beside it and links each precision from the one prefix.
cmake -S . -B build-float -G Ninja -DCMAKE_BUILD_TYPE=Release -DTORSION_WARNINGS_AS_ERRORS=ON \
  -DTORSION_BULLET_PRECISION=float "${fast_only[@]}" \
  -DTORSION_CONSUMER_ALSO_INSTALL="$PWD/build"
cmake --build build-float -j"$jobs"
# (The build without CHOLMOD is precision-independent and checked once, in the Release pass.)
ctest --test-dir build-float -j"$jobs" --output-on-failure -L "unit|cli|package" --timeout 900 \
  -E "package.builds_without_cholmod"

stage "Sanitizer + fuzz build (build-asan/, clang, ASan+UBSan)"
cmake -S . -B build-asan -G Ninja "${sanitizer_flags[@]}" "${fast_only[@]}" -DTORSION_SANITIZE=ON \
  -DTORSION_FUZZ=ON
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan -j"$jobs" --output-on-failure -L "unit|cli|fuzz" --timeout 900
