# Precompiled headers: the third-party headers every source of a target parses (Eigen, Bullet,
# GoogleTest, CLI11, nlohmann_json, pybind11) are parsed once per target instead of once per
# source (or per unity batch). They are only third-party and standard headers, never our own, so
# an edit to a Torsion header never rebuilds a precompiled header. TORSION_PCH=OFF turns them off
# (e.g. to check that every source includes what it uses).
#
# Off by default in a unity build (TORSION_UNITY_BUILD): a target then compiles a handful of
# batches, and gcc's precompiled header (165 MB per target, written and cached per test
# executable) cost more than it saved. Measured in a cold Release build on 2 cores: 42 headers,
# 530 s of compile time, against 0-1.4 s saved per batch over some 130 batches.
if(TORSION_UNITY_BUILD)
  set(_torsion_pch_default OFF)
else()
  set(_torsion_pch_default ON)
endif()
option(TORSION_PCH "Precompile the heavy third-party headers of each target" ${_torsion_pch_default})

# Header sets, by what a target uses.
set(TORSION_PCH_STD <algorithm> <array> <cmath> <functional> <map> <memory> <optional> <string>
    <vector>)
set(TORSION_PCH_SOLVER <Eigen/Core> <Eigen/Geometry> <Eigen/Sparse> <btBulletDynamicsCommon.h>)
set(TORSION_PCH_GTEST <gtest/gtest.h>)
set(TORSION_PCH_CLI <CLI/CLI.hpp>)
set(TORSION_PCH_JSON <nlohmann/json.hpp>)

# torsion_precompile_headers(TARGET SET...): SET names one of the sets above (STD, SOLVER, GTEST,
# CLI, JSON) or is a header of its own (<pybind11/pybind11.h>).
function(torsion_precompile_headers target)
  if(NOT TORSION_PCH OR NOT TARGET ${target})
    return()
  endif()
  set(headers)
  foreach(item IN LISTS ARGN)
    if(DEFINED TORSION_PCH_${item})
      list(APPEND headers ${TORSION_PCH_${item}})
    else()
      list(APPEND headers ${item})
    endif()
  endforeach()
  target_precompile_headers(${target} PRIVATE ${headers})
  # clang stamps a PCH with the time it was written, so ccache would see a new header in every
  # build and miss every source that uses it.
  if(CMAKE_CXX_COMPILER_ID MATCHES "Clang")
    target_compile_options(${target} PRIVATE "SHELL:-Xclang -fno-pch-timestamp")
  endif()
endfunction()

# A test executable: GoogleTest, plus the solver's headers when it links the library.
function(torsion_precompile_test_headers target)
  if(NOT TARGET ${target})
    return()
  endif()
  get_target_property(libs ${target} LINK_LIBRARIES)
  set(sets STD GTEST)
  if(libs MATCHES "Torsion::extension|torsion_scene|torsion_render")
    list(APPEND sets SOLVER)
  endif()
  torsion_precompile_headers(${target} ${sets})
endfunction()

# Every executable defined in DIR and its subdirectories: its precompiled headers, and
# TORSION_TEST_OPTIMIZATION. The library under test keeps the build type's optimisation; test
# code is thin glue around it, and at -O3 the Eigen expressions inlined into a test source cost
# more to compile than the whole test costs to run.
set(TORSION_TEST_OPTIMIZATION "-O1" CACHE STRING
    "Optimisation flag for the test and benchmark-free test executables (empty: the build type's)")
# With TORSION_UNITY_BUILD the GoogleTest executables compile in unity batches too, this many
# sources a batch: small enough that the larger executables still give ninja several batches to
# run side by side, large enough that GoogleTest's, Eigen's and Bullet's headers are not parsed
# and instantiated for every few tests (8 against 4: a fifth less CPU for most test executables).
# Sources of one batch share a translation unit, so their anonymous namespaces are one: a test
# source whose helpers would clash with another's (kDt, parse, sceneWith, ...) keeps them in a
# namespace named after its file.
set(TORSION_TEST_UNITY_BATCH_SIZE 8 CACHE STRING
    "Sources per unity batch of a test executable (TORSION_UNITY_BUILD)")
function(torsion_tune_test_targets dir)
  get_property(targets DIRECTORY ${dir} PROPERTY BUILDSYSTEM_TARGETS)
  foreach(target IN LISTS targets)
    get_target_property(type ${target} TYPE)
    if(NOT type STREQUAL "EXECUTABLE")
      continue()
    endif()
    get_target_property(libs ${target} LINK_LIBRARIES)
    set(sets STD)
    if(libs MATCHES "GTest::")
      list(APPEND sets GTEST)
      if(TORSION_TEST_OPTIMIZATION)
        target_compile_options(${target} PRIVATE ${TORSION_TEST_OPTIMIZATION})
      endif()
      if(TORSION_UNITY_BUILD)
        set_target_properties(${target} PROPERTIES UNITY_BUILD ON
                              UNITY_BUILD_BATCH_SIZE ${TORSION_TEST_UNITY_BATCH_SIZE})
      endif()
    endif()
    if(libs MATCHES "Torsion::extension|torsion_scene|torsion_render")
      list(APPEND sets SOLVER)
    endif()
    if(libs MATCHES "torsion_scene|torsion_render|nlohmann_json")
      list(APPEND sets JSON)
    endif()
    torsion_precompile_headers(${target} ${sets})
  endforeach()
  get_property(subdirs DIRECTORY ${dir} PROPERTY SUBDIRECTORIES)
  foreach(subdir IN LISTS subdirs)
    torsion_tune_test_targets(${subdir})
  endforeach()
endfunction()
