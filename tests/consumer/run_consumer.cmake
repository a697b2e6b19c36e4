# Installs the build tree into a scratch prefix, then configures, builds and runs an outside
# project against it. Arguments: BUILD_DIR, SOURCE_DIR, WORK_DIR, GENERATOR, PRECISION (the
# build's Bullet precision), and optionally ALSO_INSTALL: another Torsion build tree, of the other
# precision, installed into the same prefix afterwards (both side by side); LAUNCHER (compiler
# launcher, may be empty).
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}")
set(prefix "${WORK_DIR}/prefix")
if(PRECISION STREQUAL "double")
  set(other float)
else()
  set(other double)
endif()

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  message(STATUS "${out}")
endfunction()

# consume(NAME PRECISION [ARGS...]): configure, build and run the consumer in WORK_DIR/NAME; it
# must report PRECISION's btScalar.
function(consume name precision)
  run(${CMAKE_COMMAND} -S "${SOURCE_DIR}" -B "${WORK_DIR}/${name}" -G "${GENERATOR}"
      "-DCMAKE_PREFIX_PATH=${prefix}" -DCMAKE_BUILD_TYPE=Release "-DCMAKE_CXX_COMPILER_LAUNCHER=${LAUNCHER}" ${ARGN})
  run(${CMAKE_COMMAND} --build "${WORK_DIR}/${name}")
  execute_process(COMMAND "${WORK_DIR}/${name}/consumer" RESULT_VARIABLE rc OUTPUT_VARIABLE out)
  if(precision STREQUAL "double")
    set(bytes 8)
  else()
    set(bytes 4)
  endif()
  if(NOT rc EQUAL 0 OR NOT out MATCHES "consumer OK: 1 tets, btScalar is ${bytes} bytes \\(${precision} Bullet\\)")
    message(FATAL_ERROR "consumer ${name}: expected ${precision} Bullet; exit ${rc}: ${out}")
  endif()
  message(STATUS "${name}: ${out}")
endfunction()

run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${prefix}")
consume(build ${PRECISION})

# Asking this prefix for the other precision is a configure error that says what to do.
execute_process(COMMAND ${CMAKE_COMMAND} -S "${SOURCE_DIR}" -B "${WORK_DIR}/build-${other}"
                        -G "${GENERATOR}" "-DCMAKE_PREFIX_PATH=${prefix}"
                        "-DTORSION_BULLET_PRECISION=${other}"
                RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err)
string(REGEX REPLACE "[ \n]+" " " err "${err}")
if(rc EQUAL 0 OR NOT err MATCHES "built for ${PRECISION} Bullet only.*-DTORSION_BULLET_PRECISION=${other}")
  message(FATAL_ERROR "asking a ${PRECISION}-only prefix for ${other} Bullet should fail and say "
                      "how to get it; exit ${rc}:\n${out}\n${err}")
endif()
message(STATUS "consumer asking for ${other} Bullet refused, as it should be")

if(ALSO_INSTALL)
  run(${CMAKE_COMMAND} --install "${ALSO_INSTALL}" --prefix "${prefix}")
  consume(build-both-${other} ${other} "-DTORSION_BULLET_PRECISION=${other}")
  consume(build-both-${PRECISION} ${PRECISION} "-DTORSION_BULLET_PRECISION=${PRECISION}")
  consume(build-both-default double)  # no request: double, the build's default
endif()
message(STATUS "consumer checks passed")
