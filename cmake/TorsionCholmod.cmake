# SuiteSparse CHOLMOD as one imported target, SuiteSparse::CHOLMOD. Debian's SuiteSparse 5.x ships
# neither a CMake package nor pkg-config files for it, so we find the header and library.
# Installed with the package so consumers get the same target.

if(NOT TARGET SuiteSparse::CHOLMOD)
  find_path(TORSION_CHOLMOD_INCLUDE_DIR cholmod.h PATH_SUFFIXES suitesparse)
  find_library(TORSION_CHOLMOD_LIBRARY cholmod)
  if(NOT TORSION_CHOLMOD_INCLUDE_DIR OR NOT TORSION_CHOLMOD_LIBRARY)
    message(FATAL_ERROR "CHOLMOD not found: install Debian's libsuitesparse-dev (scripts/setup.sh does)")
  endif()
  add_library(SuiteSparse::CHOLMOD UNKNOWN IMPORTED)
  set_target_properties(SuiteSparse::CHOLMOD PROPERTIES
    IMPORTED_LOCATION "${TORSION_CHOLMOD_LIBRARY}"
    INTERFACE_INCLUDE_DIRECTORIES "${TORSION_CHOLMOD_INCLUDE_DIR}")
endif()
