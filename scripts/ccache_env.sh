# Sourced by scripts/test.sh and scripts/main.sh: how their builds use the compiler cache.
# - CCACHE_BASEDIR: paths under the checkout are hashed relative to it, so a fresh clone of the
#   same tree in another folder (as CI makes) hits the entries an earlier build left.
# - CCACHE_NOHASHDIR: the sanitizer builds keep line tables (-g...), which would otherwise hash
#   the build directory too.
# - CCACHE_SLOPPINESS: the precompiled headers (cmake/TorsionPrecompiledHeaders.cmake) are cached
#   only when ccache may ignore their time stamps and the macros defined before them.
# - CCACHE_STATSLOG: this run's own hits and misses, printed by ccache_report at the end.
# The cache itself stays where ccache keeps it (~/.cache/ccache, or CCACHE_DIR when set).
export CCACHE_BASEDIR="$PWD"
export CCACHE_NOHASHDIR=1
export CCACHE_SLOPPINESS=pch_defines,time_macros,include_file_mtime,include_file_ctime
# Four builds of the project take about 2 GB of objects; keep two trees' worth.
export CCACHE_MAXSIZE="${CCACHE_MAXSIZE:-6G}"
ccache_statslog=$(mktemp -t torsion-ccache-stats.XXXXXX)
export CCACHE_STATSLOG="$ccache_statslog"

# Prints this run's cache statistics (hits, misses) in one block; a no-op without ccache.
ccache_report() {
  if command -v ccache >/dev/null 2>&1 && [ -s "$ccache_statslog" ]; then
    echo "== Compiler cache (ccache) for this run"
    # The first block: cacheable calls, hits (direct and preprocessed) and misses.
    ccache --show-log-stats 2>/dev/null | awk 'NR > 1 && /^[^ ]/ {exit} {print}' || true
  fi
  rm -f "$ccache_statslog"
}
