# Builds examples/ against the installed package, as a user's project would, with the README's C++
# snippet extracted from README.md, and runs every program. Arguments: BUILD_DIR, PROJECT_DIR,
# WORK_DIR, GENERATOR, MESH (a mesh the README snippet reads from its working directory),
# LAUNCHER (compiler launcher, may be empty).
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/run")

function(run)
  execute_process(COMMAND ${ARGN} WORKING_DIRECTORY "${WORK_DIR}/run" RESULT_VARIABLE rc
                  OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

# The README's first ```cpp block, exactly as written.
file(READ "${PROJECT_DIR}/README.md" readme)
string(FIND "${readme}" "```cpp\n" start)
if(start EQUAL -1)
  message(FATAL_ERROR "README.md has no ```cpp block")
endif()
math(EXPR start "${start} + 7")
string(SUBSTRING "${readme}" ${start} -1 rest)
string(FIND "${rest}" "```" stop)
string(SUBSTRING "${rest}" 0 ${stop} snippet)
file(WRITE "${WORK_DIR}/readme_snippet.cpp" "${snippet}")

run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")
run(${CMAKE_COMMAND} -S "${PROJECT_DIR}/examples" -B "${WORK_DIR}/build" -G "${GENERATOR}"
    "-DCMAKE_PREFIX_PATH=${WORK_DIR}/prefix" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}"
    "-DREADME_SNIPPET=${WORK_DIR}/readme_snippet.cpp" -DTORSION_EXAMPLES_STRICT=ON)
run(${CMAKE_COMMAND} --build "${WORK_DIR}/build")

get_filename_component(mesh_base "${MESH}" NAME_WE)
get_filename_component(mesh_dir "${MESH}" DIRECTORY)
file(COPY "${mesh_dir}/${mesh_base}.node" "${mesh_dir}/${mesh_base}.ele" DESTINATION "${WORK_DIR}/run")
run("${WORK_DIR}/build/readme_snippet")
run("${WORK_DIR}/build/own_world")
run("${WORK_DIR}/build/multibody_gripper")
run("${WORK_DIR}/build/anchor_pendulum")
if(EXISTS "${WORK_DIR}/build/bullet_import")
  run("${WORK_DIR}/build/bullet_import" "${WORK_DIR}/run/boxes.bullet")
else()
  message(FATAL_ERROR "bullet_import was not built: install libbullet-extras-dev")
endif()
message(STATUS "examples OK")
