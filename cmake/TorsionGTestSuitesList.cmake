# Run by torsion_add_gtest_suites (cmake/TorsionGTestSuites.cmake) after each build of a test
# executable: lists its GoogleTest suites and writes one add_test per suite to `output`.
#   cmake -D executable=EXE -D working_directory=DIR -D args_file=FILE -D output=FILE -P this
# args_file sets `exclude` (filter patterns) and `properties` (set_tests_properties arguments).
include("${args_file}")

set(filter "*")
if(exclude)
  list(JOIN exclude ":" negative)
  set(filter "*-${negative}")
endif()
execute_process(COMMAND "${executable}" --gtest_list_tests "--gtest_filter=${filter}"
                WORKING_DIRECTORY "${working_directory}" TIMEOUT 60
                OUTPUT_VARIABLE listing ERROR_VARIABLE errors RESULT_VARIABLE status)
if(NOT status EQUAL 0)
  message(FATAL_ERROR "${executable} --gtest_list_tests failed (${status}):\n${errors}")
endif()

# The listing: "Suite." on a line of its own (a typed suite adds "  # TypeParam = ..."), then its
# cases indented by two spaces (a parameterised case adds "  # GetParam() = ...").
string(REPLACE ";" "\\;" listing "${listing}")
string(REPLACE "\n" ";" lines "${listing}")
set(suites)
set(suite "")
foreach(line IN LISTS lines)
  if(line MATCHES "^([^ #][^ ]*)\\.( |$)")
    set(suite "${CMAKE_MATCH_1}")
  elseif(suite AND line MATCHES "^  ([^ #]+)" AND NOT CMAKE_MATCH_1 MATCHES "^DISABLED_"
         AND NOT suite MATCHES "(^|/)DISABLED_")
    list(APPEND suites "${suite}")
  endif()
endforeach()
list(REMOVE_DUPLICATES suites)
if(NOT suites)
  message(FATAL_ERROR "${executable} lists no test (filter ${filter})")
endif()

list(JOIN properties " " properties)
set(text "")
foreach(suite IN LISTS suites)
  set(suite_filter "${suite}.*")
  if(exclude)
    string(APPEND suite_filter "-${negative}")
  endif()
  string(APPEND text "add_test([==[${suite}]==] [==[${executable}]==] [==[--gtest_filter=${suite_filter}]==])\n"
         "set_tests_properties([==[${suite}]==] PROPERTIES WORKING_DIRECTORY [==[${working_directory}]==] ${properties})\n")
endforeach()
# Whole or absent: CTest never reads half a list.
file(WRITE "${output}.tmp" "${text}")
file(RENAME "${output}.tmp" "${output}")
