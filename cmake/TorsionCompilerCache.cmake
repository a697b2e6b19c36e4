# Compiler cache: when ccache is installed (scripts/setup.sh installs it), every compilation goes
# through it, so a tree built before on this machine recompiles only what changed. A launcher the
# user set (CMAKE_CXX_COMPILER_LAUNCHER) wins; TORSION_CCACHE=OFF turns the cache off.
# scripts/ccache_env.sh sets what makes the cache hit across clones and with precompiled headers
# (a base directory, the PCH sloppiness); without it ccache is still correct, it just caches less.
option(TORSION_CCACHE "Compile through ccache when it is installed" ON)

if(TORSION_CCACHE AND NOT CMAKE_CXX_COMPILER_LAUNCHER)
  find_program(TORSION_CCACHE_PROGRAM ccache)
  mark_as_advanced(TORSION_CCACHE_PROGRAM)
  if(TORSION_CCACHE_PROGRAM)
    set(CMAKE_CXX_COMPILER_LAUNCHER "${TORSION_CCACHE_PROGRAM}")
    message(STATUS "Compiler cache: ${TORSION_CCACHE_PROGRAM}")
  endif()
endif()
