# A permissive build: Torsion configured with TORSION_CHOLMOD=OFF (library only), installed, and a
# consumer on it whose direct solver factorises with Eigen and matches CG; neither the package nor
# the program asks for CHOLMOD. Arguments: SOURCE_DIR (Torsion), CONSUMER_DIR, WORK_DIR,
# GENERATOR, PRECISION, LAUNCHER (compiler launcher, may be empty), PREBUILT (optional: a built
# Torsion tree configured with TORSION_CHOLMOD=OFF, installed instead of building one here).
set(prefix "${WORK_DIR}/prefix")
file(REMOVE_RECURSE "${prefix}" "${WORK_DIR}/consumer")

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}" PARENT_SCOPE)
endfunction()

if(PREBUILT)
  # Installing a tree that was built with CHOLMOD would pass this test for the wrong reason.
  file(STRINGS "${PREBUILT}/CMakeCache.txt" cholmod_setting REGEX "^TORSION_CHOLMOD:BOOL=")
  if(NOT cholmod_setting STREQUAL "TORSION_CHOLMOD:BOOL=OFF")
    message(FATAL_ERROR "${PREBUILT} is not configured with TORSION_CHOLMOD=OFF ('${cholmod_setting}')")
  endif()
  set(tree "${PREBUILT}")
else()
  # The library tree is kept between runs (only its changed batches rebuild); unity batches
  # (TORSION_UNITY_BUILD) halve this second build of the library in a clean test run.
  set(tree "${WORK_DIR}/torsion")
  run(${CMAKE_COMMAND} -S "${SOURCE_DIR}" -B "${tree}" -G "${GENERATOR}"
      -DCMAKE_BUILD_TYPE=Release -DTORSION_CHOLMOD=OFF -DTORSION_BUILD_DEMOS=OFF
      -DTORSION_UNITY_BUILD=ON -DTORSION_BUILD_TESTS=OFF -DTORSION_BUILD_BENCHMARKS=OFF
      "-DTORSION_BULLET_PRECISION=${PRECISION}" "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}")
  run(${CMAKE_COMMAND} --build "${tree}")
endif()
run(${CMAKE_COMMAND} --install "${tree}" --prefix "${prefix}")
file(GLOB_RECURSE cmake_files "${prefix}/*.cmake")
foreach(file ${cmake_files})
  file(STRINGS "${file}" mentions REGEX "SuiteSparse::CHOLMOD|libcholmod")
  if(mentions OR file MATCHES "TorsionCholmod.cmake$")
    message(FATAL_ERROR "${file} asks for CHOLMOD in a TORSION_CHOLMOD=OFF package: ${mentions}")
  endif()
endforeach()

run(${CMAKE_COMMAND} -S "${CONSUMER_DIR}" -B "${WORK_DIR}/consumer" -G "${GENERATOR}"
    "-DCMAKE_PREFIX_PATH=${prefix}" -DCMAKE_BUILD_TYPE=Release)
run(${CMAKE_COMMAND} --build "${WORK_DIR}/consumer" --verbose)
if(last_output MATCHES "libcholmod|-lcholmod")
  message(FATAL_ERROR "the consumer links CHOLMOD:\n${last_output}")
endif()
run("${WORK_DIR}/consumer/direct_solver")
if(NOT last_output MATCHES "direct solver \\(Eigen SimplicialLLT\\)")
  message(FATAL_ERROR "expected Eigen's factorisation: ${last_output}")
endif()
message(STATUS "${last_output}")
