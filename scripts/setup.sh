#!/usr/bin/env bash
# Installs the Debian packages Torsion needs, only those that are missing.
#
#   scripts/setup.sh           everything: building, testing, the examples
#   scripts/setup.sh --build   only what the builds need (compilers, libraries, headers): a test
#                              run (scripts/test.sh) installs the rest in the background while it
#                              compiles
#
# As root it runs apt-get itself. As another user it uses `sudo -n` when that works without a
# password; otherwise it prints the exact apt-get command to run and exits with status 1, changing
# nothing. Nothing is downloaded from anywhere but Debian's archive.
#
# apt-get's own output (thousands of lines on a fresh machine) goes to a log file,
# build/setup.log (TORSION_SETUP_LOG overrides it); this prints one line per stage, and on a
# failure the log's last lines, so every error stays visible.
set -euo pipefail

# What the Release build needs (it compiles the library, the tool, the Python module, the tests
# and the benchmarks).
build_packages=(
  # build; ccache: a tree built before on this machine recompiles only what changed
  cmake ninja-build g++ pkg-config ccache
  # libraries
  libbullet-dev libbullet-extras-dev libeigen3-dev libsuitesparse-dev libccd-dev libtbb-dev
  # an optimised BLAS for CHOLMOD's supernodal factorisation, single-threaded (the library's
  # threads are its own): Debian's reference BLAS, the default, factorises 5x slower
  libopenblas0-serial
  libcli11-dev nlohmann-json3-dev libpng-dev
  libosmesa6-dev libglfw3-dev
  # the SpaceMouse device (optional in CMake; the spacenavd daemon is the user's to install)
  libspnav-dev
  # the network device's packet authentication (HMAC-SHA256, random session ids)
  libsodium-dev
  # tests and benchmarks
  libgtest-dev libbenchmark-dev
  # the Python package (`import torsion`)
  python3-dev pybind11-dev python3-numpy
  # the ParaView series: zlib compresses it
  zlib1g-dev
)
# What the tests, the sanitizer builds and the examples need besides.
other_packages=(
  # the viewer's test: a virtual X server and Mesa's software GLX
  xvfb xauth libgl1-mesa-dri libglx-mesa0
  # the sanitizer builds: clang + its runtime (also for the libFuzzer targets)
  clang libclang-rt-14-dev
  # mesh generation (`torsion mesh cylinder` runs the tetgen command)
  tetgen
  # the Python package's tests and examples
  python3-pytest python3-matplotlib
  # examples/python/dask_sweep.py: a sweep fanned out over Dask's distributed scheduler
  python3-distributed
  # `pip install --no-build-isolation .` into a virtual environment (scikit-build runs CMake), and
  # `python3 -m build --wheel --no-isolation`; tests/python/pip_install_check.py does both
  python3-venv python3-skbuild python3-build
  # the ParaView series tests read it back with meshio and VTK
  python3-meshio python3-vtk9
  # instruction counts per step (tests/bench/bench_python_step.py --instructions: callgrind)
  valgrind
  # static analysis in CI (scripts/clang_tidy.sh, the committed .clang-tidy)
  clang-tidy-14
)

case "${1:-}" in
  --build) packages=("${build_packages[@]}") ;;
  "") packages=("${build_packages[@]}" "${other_packages[@]}") ;;
  *)
    echo "usage: scripts/setup.sh [--build]" >&2
    exit 2
    ;;
esac

missing=()
for p in "${packages[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
    missing+=("$p")
  fi
done

if [ ${#missing[@]} -eq 0 ]; then
  echo "setup: all ${#packages[@]} Debian packages present"
  exit 0
fi

echo "setup: installing ${#missing[@]} missing Debian package(s): ${missing[*]}"
if [ "$(id -u)" -eq 0 ]; then
  as_root=()
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
  as_root=(sudo -n)
else
  echo "setup: not root and no password-less sudo; run this, then try again:" >&2
  echo "  sudo apt-get update && sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
  exit 1
fi
export DEBIAN_FRONTEND=noninteractive
log=${TORSION_SETUP_LOG:-$(cd "$(dirname "$0")/.." && pwd)/build/setup.log}
mkdir -p "$(dirname "$log")"
: >"$log"
# Runs one stage with its output in the log; on failure shows the log's end and stops.
quietly() {
  local what=$1
  shift
  echo "setup: $what (log: $log)"
  if ! "$@" >>"$log" 2>&1; then
    echo "setup: $what failed; the last lines of $log:" >&2
    tail -n 40 "$log" >&2
    exit 1
  fi
}
quietly "updating the package lists" "${as_root[@]}" apt-get update -q
quietly "installing ${#missing[@]} package(s)" \
  "${as_root[@]}" apt-get install -y -q --no-install-recommends "${missing[@]}"
echo "setup: done"
