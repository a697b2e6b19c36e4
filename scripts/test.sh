#!/usr/bin/env bash
# The whole test suite, from a fresh machine. `.ci/run` calls exactly this. Stages:
#   1. set-up (scripts/setup.sh: the Debian packages, only those missing): what the Release build
#      needs; the rest (clang, test tools, Python's test modules) installs in the background during
#      the Release build, and the next stage waits for it;
#   2. Release build (build/ci/release/, gcc, double Bullet, warnings as errors);
#   3. the float-Bullet library without CHOLMOD (build-float/, clang): the package tests install it
#      beside the Release build's (a consumer links each precision from one prefix) and alone (a
#      consumer's direct solver works without CHOLMOD);
#   4. every CTest test of the Release build;
#   5. clang-tidy over extension/ and device/;
#   6. ThreadSanitizer (build-tsan/): the haptic loop's thread, its buffers, the runtime, and the
#      device fault cases (bad readings, dead peers, hung plug-ins, watchdogs);
#   7. ASan + UBSan on float Bullet (build-asan/, clang): the fast tests and the fuzzers.
# Every build compiles through ccache (scripts/ccache_env.sh): on a machine that built the same
# tree before, the builds take seconds. Each stage's wall time and the cache's hits and misses
# are printed at the end, whether the run passes or fails.
set -euo pipefail
cd "$(dirname "$0")/.."
jobs=$(nproc 2>/dev/null || echo 2)
# shellcheck source=scripts/ccache_env.sh
source scripts/ccache_env.sh
# shellcheck source=scripts/stages.sh
source scripts/stages.sh
trap 'rc=$?; report_stages; ccache_report; exit $rc' EXIT

# Every build here may start clean, so the libraries, the tool and the Python module compile as
# unity batches (TORSION_UNITY_BUILD), without precompiled headers (their default in a unity build:
# cmake/TorsionPrecompiledHeaders.cmake). The extra builds compile only what their stage runs: the
# fast labels' executables (no physics, regression or render tests, no Python module, no
# benchmarks). The sanitizers keep line tables, not full debug information, which is enough for
# their reports. ASan at -O2: -O1 compiles a fifth faster but runs its tests twice as long. TSan
# at -O0: its tests are the haptic loop's, paced by the clock rather than by the CPU (the FEM bars
# they step have at most 200 tets), and its build takes a quarter less CPU than at -O1 (213 s
# against 276 s). The sanitizers' GoogleTest executables (TORSION_TEST_OPTIMIZATION) at -O0: clang
# compiles them in half the CPU of -O1 (ASan: 223 s against 403 s), and the unit tests, whose work
# is mostly the library's, run 86 s of CPU longer: 45 s of wall time off the stage.
unity=(-DTORSION_UNITY_BUILD=ON)
fast_only=("${unity[@]}" -DTORSION_BUILD_SLOW_TESTS=OFF -DTORSION_PYTHON=OFF -DTORSION_BUILD_BENCHMARKS=OFF
  -DTORSION_TEST_OPTIMIZATION=-O0)
sanitizer_flags=(-DCMAKE_BUILD_TYPE=RelWithDebInfo -DCMAKE_CXX_COMPILER=clang++)
asan_flags=("${sanitizer_flags[@]}" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O2 -gline-tables-only -DNDEBUG")
tsan_flags=("${sanitizer_flags[@]}" "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O0 -gline-tables-only -DNDEBUG")

stage "Set-up (scripts/setup.sh --build)"
bash scripts/setup.sh --build
# On a fresh machine the rest is some 150 packages (VTK, SciPy, clang), about two minutes of
# downloading and unpacking that the compilers need not wait for.
mkdir -p build
TORSION_SETUP_LOG=$PWD/build/setup-rest.log bash scripts/setup.sh >build/setup-rest.out 2>&1 &
setup_rest=$!
# wait_for_setup: the background set-up's end; its output, and a failure stops the run.
wait_for_setup() {
  local rc=0
  wait "$setup_rest" || rc=$?
  cat build/setup-rest.out
  [ "$rc" -eq 0 ] || { echo "set-up of the test packages failed (exit $rc)" >&2; exit "$rc"; }
}

# The Release build lies three folders below the tree, as deep as scikit-build's own build folder
# (_skbuild/<platform>/cmake-build) lies below its copy of the tree in the pip test
# (python.pip_install): ccache writes the paths under its base directory relative to the compile's
# folder, so only at equal depths are pip's compilations this build's, and hit the cache.
release=build/ci/release
stage "Release build ($release/)"
configure "$release" -DCMAKE_BUILD_TYPE=Release -DTORSION_WARNINGS_AS_ERRORS=ON "${unity[@]}" \
  -DTORSION_CONSUMER_ALSO_INSTALL="$PWD/build-float" -DTORSION_CONSUMER_WITHOUT_CHOLMOD="$PWD/build-float"
build "$release"

# The libraries a consumer links, once more in the two settings a package may differ in: float
# Bullet and no CHOLMOD (the GPL-free build). Float Bullet's behaviour (the tests) is checked in
# the sanitizer build, stage 7.
stage "Float-Bullet library without CHOLMOD (build-float/, clang), for the package tests"
# clang came with the rest of the set-up, in the background during the Release build.
wait_for_setup
# With clang at -Og: clang compiles the library's batches in 60 % of gcc's time at the same level
# (its largest batch: 45 s against 74 s; the stage 72 s against 123 s), and -Og a quarter faster
# than -O3 (the consumers it serves run a few steps of a small mesh). Its -Wconversion holds float's
# narrowing to the same errors as gcc's; gcc compiles every target in the Release build.
configure build-float -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_FLAGS_RELEASE=-Og -DNDEBUG" \
  -DCMAKE_CXX_COMPILER=clang++ -DTORSION_WARNINGS_AS_ERRORS=ON "${unity[@]}" \
  -DTORSION_BULLET_PRECISION=float -DTORSION_CHOLMOD=OFF -DTORSION_BUILD_TESTS=OFF \
  -DTORSION_BUILD_DEMOS=OFF -DTORSION_BUILD_BENCHMARKS=OFF
build build-float

# ctest runs $jobs tests at once: each takes one thread (TORSION_THREADS, the default of a world
# that asks for 0, i.e. all cores), so that two-thread worlds do not contend for the same cores
# (a third more CPU time, measured). A test that is about threads asks for its count itself.
stage "Test suite ($release/)"
seed_test_costs "$release" tests/ctest_costs/release.txt
TORSION_THREADS=1 ctest --test-dir "$release" -j"$jobs" --output-on-failure
# The pytest suite is one CTest test (python.pytest); its own count of tests:
grep -hEo "^[0-9]+ passed.* in [0-9.]+s" "$release"/Testing/Temporary/LastTest.log | tail -1 |
  sed 's/^/== pytest (label python): /' || true

stage "clang-tidy (.clang-tidy) over extension/ and device/"
# From a configured, unbuilt tree without precompiled headers (clang-tidy cannot read gcc's),
# with the Python module, whose bindings live under extension/.
configure build-tidy -DCMAKE_BUILD_TYPE=Release "${unity[@]}" -DTORSION_PCH=OFF \
  -DTORSION_BUILD_TESTS=OFF -DTORSION_BUILD_BENCHMARKS=OFF
bash scripts/clang_tidy.sh build-tidy

stage "ThreadSanitizer build (build-tsan/, clang): the haptic loop, its buffers, the runtime, device faults"
configure build-tsan "${tsan_flags[@]}" "${fast_only[@]}" -DTORSION_TSAN=ON \
  -DTORSION_BUILD_DEMOS=OFF
build build-tsan --target torsion_device_tests torsion_bullet_tests
TSAN_OPTIONS="halt_on_error=1 second_deadlock_stack=1" \
  ctest --test-dir build-tsan -j"$jobs" --output-on-failure \
  -R "HapticLoop|TripleBuffer|NetworkDevice|NetworkPeer|PacketAuthentication|PluginDevice|WrenchWatchdog|WrenchSafety|SafetyFilter|ReadingCheck|Passivity|UserWorldHaptics"

# One build for two things only it can catch: memory and undefined-behaviour errors (ASan, UBSan,
# the fuzzers), and float Bullet (Debian's default btScalar, the one most programs link): the
# unit and CLI tests run on float here, while the Release suite runs on double. (Warnings are not
# errors here: clang's -Wdouble-promotion flags every btScalar widened to double, which is exact
# and intended; float's narrowing is an error in the gcc float build, stage 3.)
stage "Sanitizer + fuzz build on float Bullet (build-asan/, clang, ASan+UBSan)"
configure build-asan "${asan_flags[@]}" "${fast_only[@]}" -DTORSION_SANITIZE=ON \
  -DTORSION_FUZZ=ON -DTORSION_BULLET_PRECISION=float
build build-asan
seed_test_costs build-asan tests/ctest_costs/sanitizers.txt
TORSION_THREADS=1 ASAN_OPTIONS=detect_leaks=1 UBSAN_OPTIONS=print_stacktrace=1 \
  ctest --test-dir build-asan -j"$jobs" --output-on-failure -L "unit|cli|fuzz"
