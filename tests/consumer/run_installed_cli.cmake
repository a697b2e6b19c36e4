# The installed `torsion` finds its demo data from where it is, not from a path compiled into it:
# install into a scratch prefix, move the prefix elsewhere, and run the moved program with an empty
# environment from a scratch directory. The source and build trees are left alone; that the moved
# program cannot reach them is shown by their paths being absent from its bytes.
# Arguments: BUILD_DIR, SOURCE_DIR, WORK_DIR, PROGRAM (the installed file name, torsion or
# torsion-float).
file(REMOVE_RECURSE "${WORK_DIR}")
file(MAKE_DIRECTORY "${WORK_DIR}/scratch")

function(run)
  execute_process(COMMAND ${ARGN} RESULT_VARIABLE rc OUTPUT_VARIABLE out ERROR_VARIABLE err
                  WORKING_DIRECTORY "${WORK_DIR}/scratch")
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "failed (${rc}): ${ARGN}\n${out}\n${err}")
  endif()
  set(last_output "${out}${err}" PARENT_SCOPE)
endfunction()

run(${CMAKE_COMMAND} --install "${BUILD_DIR}" --prefix "${WORK_DIR}/prefix")
file(RENAME "${WORK_DIR}/prefix" "${WORK_DIR}/moved")
set(program "${WORK_DIR}/moved/bin/${PROGRAM}")
foreach(dir "${SOURCE_DIR}" "${BUILD_DIR}")
  file(STRINGS "${program}" found REGEX "${dir}")
  if(found)
    message(FATAL_ERROR "${program} holds the path ${dir}: ${found}")
  endif()
endforeach()
foreach(file demos/scenes/drop.json assets/meshes/cylinder_2430.node
             assets/trajectories/turn_neck.json assets/bullet/boxes.bullet)
  if(NOT EXISTS "${WORK_DIR}/moved/share/torsion/${file}")
    message(FATAL_ERROR "share/torsion/${file} was not installed")
  endif()
endforeach()

set(clean_env env -i "PATH=/usr/bin:/bin" "HOME=${WORK_DIR}/scratch")
run(${clean_env} "${program}" --version)
if(NOT last_output MATCHES "^torsion [0-9]+\\.[0-9]+\\.[0-9]+ \\(git [0-9a-f]+(-dirty)?, (double|float) Bullet\\)")
  message(FATAL_ERROR "--version printed: ${last_output}")
endif()
message(STATUS "${last_output}")
run(${clean_env} "${program}" run drop --out drop)
file(READ "${WORK_DIR}/scratch/drop/summary.json" summary)
string(JSON completed GET "${summary}" completed)
string(JSON steps GET "${summary}" steps)
if(NOT completed OR NOT steps EQUAL 150)
  message(FATAL_ERROR "the installed run did not complete its 150 steps: ${summary}")
endif()
# TORSION_SCENE_PATH still comes first.
file(MAKE_DIRECTORY "${WORK_DIR}/my_scenes")
file(READ "${WORK_DIR}/moved/share/torsion/demos/scenes/drop.json" drop)
string(REPLACE "../../assets" "${WORK_DIR}/moved/share/torsion/assets" drop "${drop}")
string(JSON drop SET "${drop}" steps 7)
file(WRITE "${WORK_DIR}/my_scenes/drop.json" "${drop}")
run(${clean_env} "TORSION_SCENE_PATH=${WORK_DIR}/my_scenes" "${program}" run drop --out mine)
file(READ "${WORK_DIR}/scratch/mine/summary.json" summary)
string(JSON steps GET "${summary}" steps)
if(NOT steps EQUAL 7)
  message(FATAL_ERROR "TORSION_SCENE_PATH's drop.json (7 steps) was not the one run: ${summary}")
endif()
# The example device plug-in is installed with it and found by its file name, a link delay set
# in its configuration.
run(${clean_env} "${program}" run twist_cylinder_2430 --device
    "hand=plugin:libtorsion_simulated_device.so:delay=0.02" --haptics lockstep --steps 5
    --threads 1 --out plugin)
if(NOT last_output MATCHES "simulated 0.3 kg, 200 Hz motors, 20 ms delay")
  message(FATAL_ERROR "the installed plug-in did not run with its delay: ${last_output}")
endif()
message(STATUS "installed torsion ran the demo scene from its moved prefix")
