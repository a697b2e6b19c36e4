#!/usr/bin/env bash
# The whole test suite, from a fresh machine: set-up, Release build, every CTest test, clang-tidy
# over the libraries, the fast tests again on float Bullet, then a clang build with ASan+UBSan
# that runs the unit tests again and fuzzes each mesh reader for a bounded time. `.ci/run` calls
# exactly this.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)

bash scripts/setup.sh

echo "== Release build (build/)"
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release -DTORSION_WARNINGS_AS_ERRORS=ON
cmake --build build -j"$jobs"
echo "== Test suite"
ctest --test-dir build -j"$jobs" --output-on-failure --timeout 900
# The pytest suite is one CTest test (python.pytest); its own count of tests:
grep -hEo "^[0-9]+ passed.* in [0-9.]+s" build/Testing/Temporary/LastTest.log | tail -1 |
  sed 's/^/== pytest (label python): /' || true
echo "== clang-tidy (.clang-tidy) over extension/ and device/, from build/compile_commands.json"
bash scripts/clang_tidy.sh build

echo "== ThreadSanitizer build (build-tsan/, clang): the haptic loop's thread, its buffers, the runtime"
cmake -S . -B build-tsan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DTORSION_TSAN=ON -DTORSION_BUILD_BENCHMARKS=OFF -DTORSION_BUILD_DEMOS=OFF
cmake --build build-tsan -j"$jobs" --target torsion_device_tests torsion_bullet_tests
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest --test-dir build-tsan -j"$jobs" --output-on-failure --timeout 900 \
  -R "HapticLoop|TripleBuffer|NetworkDevice|PluginDevice|UserWorldHaptics"

echo "== Float-Bullet build (build-float/): Debian's default Bullet; fast tests and the package"
# The same code on pkg-config `bullet` (btScalar = float), the Bullet most programs link. The
# package test also installs build/ beside it and links each precision from the one prefix.
cmake -S . -B build-float -G Ninja -DCMAKE_BUILD_TYPE=Release -DTORSION_WARNINGS_AS_ERRORS=ON \
  -DTORSION_BULLET_PRECISION=float -DTORSION_BUILD_BENCHMARKS=OFF \
  -DTORSION_CONSUMER_ALSO_INSTALL="$PWD/build"
cmake --build build-float -j"$jobs"
# (The build without CHOLMOD is precision-independent and checked once, in the Release pass.)
ctest --test-dir build-float -j"$jobs" --output-on-failure -L "unit|cli|package" --timeout 900 \
  -E "package.builds_without_cholmod"

echo "== Sanitizer + fuzz build (build-asan/, clang, ASan+UBSan)"
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++ \
  -DTORSION_SANITIZE=ON -DTORSION_FUZZ=ON -DTORSION_BUILD_BENCHMARKS=OFF
cmake --build build-asan -j"$jobs"
ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan -j"$jobs" --output-on-failure -L "unit|cli|fuzz" --timeout 900
