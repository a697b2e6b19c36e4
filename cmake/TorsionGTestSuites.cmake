# torsion_add_gtest_suites(TARGET [EXCLUDE PATTERN...] PROPERTIES NAME VALUE...)
#
# One CTest test per GoogleTest suite of TARGET, for executables of many short tests (label unit):
# the test named after the suite runs `TARGET --gtest_filter=Suite.*` in one process.
# gtest_discover_tests starts a process per test case instead, and for a test of a few
# milliseconds that start costs more than the test: about 25 ms in Release and 100 ms under
# ASan, over some 600 cases. The suites are listed after each build of TARGET (POST_BUILD, from
# `--gtest_list_tests`), so a new test needs no CMake edit. EXCLUDE takes GoogleTest filter
# patterns (Suite.Case or Suite.*) left out of every suite, e.g. a slow case registered on its own
# with another label. DISABLED_ suites and cases are left out, as GoogleTest itself does.
set(_torsion_gtest_suites_script "${CMAKE_CURRENT_LIST_DIR}/TorsionGTestSuitesList.cmake")

function(torsion_add_gtest_suites target)
  cmake_parse_arguments(PARSE_ARGV 1 arg "" "" "EXCLUDE;PROPERTIES")
  set(prefix "${CMAKE_CURRENT_BINARY_DIR}/${target}")
  set(suites_file "${prefix}_suites.cmake")
  # The arguments the listing script needs beyond the executable, written once at configure time
  # (a list on a command line would need escaping through two shells).
  file(CONFIGURE OUTPUT "${prefix}_suites_args.cmake" CONTENT
       "set(exclude [==[${arg_EXCLUDE}]==])\nset(properties [==[${arg_PROPERTIES}]==])\n")
  add_custom_command(TARGET ${target} POST_BUILD
    COMMAND "${CMAKE_COMMAND}" -D "executable=$<TARGET_FILE:${target}>"
            -D "working_directory=${CMAKE_CURRENT_BINARY_DIR}" -D "args_file=${prefix}_suites_args.cmake"
            -D "output=${suites_file}" -P "${_torsion_gtest_suites_script}"
    BYPRODUCTS "${suites_file}"
    VERBATIM)
  # CTest reads the list when it runs; before the first build it finds a placeholder test that
  # fails, naming the missing executable, as gtest_discover_tests does.
  set(include_file "${prefix}_suites_include.cmake")
  file(CONFIGURE OUTPUT "${include_file}" CONTENT
       "if(EXISTS [==[${suites_file}]==])\n  include([==[${suites_file}]==])\nelse()\n  add_test(${target}_NOT_BUILT ${target}_NOT_BUILT)\nendif()\n")
  set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${include_file}")
endfunction()
