# Warnings and sanitizers, applied per target so consumers of the installed package inherit none.
# Third-party headers (Eigen, Bullet, pybind11, GoogleTest, nlohmann_json) come in through
# imported targets, whose include directories are SYSTEM: these flags judge our own code only.

function(torsion_apply_warnings target)
  if(CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    target_compile_options(${target} PRIVATE -Wall -Wextra -Wpedantic -Wshadow -Wnon-virtual-dtor
                                             -Wold-style-cast -Wcast-align -Woverloaded-virtual
                                             -Wdouble-promotion -Wformat=2)
    # Implicit narrowing and sign changes are mistakes in our code: say so with a cast. Not yet
    # in tests/ on float Bullet, whose tests still pass double literals straight to Bullet
    # (btVector3(0.1, ...) and the like); everywhere else, both precisions.
    get_target_property(_source_dir ${target} SOURCE_DIR)
    string(FIND "${_source_dir}/" "${PROJECT_SOURCE_DIR}/tests/" _in_tests)
    if(NOT (TORSION_BULLET_PRECISION STREQUAL "float" AND _in_tests EQUAL 0))
      target_compile_options(${target} PRIVATE -Wconversion -Wsign-conversion)
    endif()
    # clang's -Wdouble-promotion also flags a btScalar widened to double where it is stored or
    # passed, which gcc's does not: on float Bullet that is every value read from Bullet, exact
    # and intended, so for clang on float Bullet it is off.
    if(CMAKE_CXX_COMPILER_ID MATCHES "Clang" AND TORSION_BULLET_PRECISION STREQUAL "float")
      target_compile_options(${target} PRIVATE -Wno-double-promotion)
    endif()
    if(TORSION_WARNINGS_AS_ERRORS)
      target_compile_options(${target} PRIVATE -Werror)
    endif()
  endif()
endfunction()

if(TORSION_SANITIZE)
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    message(FATAL_ERROR "TORSION_SANITIZE needs GCC or Clang")
  endif()
  # Global on purpose: every object in the process must be instrumented alike. Four of UBSan's
  # checks are left out because ASan (or the CPU, under ASan's fault handler) already catches what
  # they look for, and they were nearly half of the sanitizer's compile cost (clang 14, the library's
  # largest batch: 75 s with them, 56 s without alignment and null, 34 s with no sanitizer):
  # - object-size (a static bound on an access): ASan checks every access against its object's
  #   real bounds; it made the batches a fifth slower to compile;
  # - pointer-overflow (pointer arithmetic that wraps): an access through such a pointer is out of
  #   bounds, which ASan reports; it instruments every index computation Eigen and Bullet inline;
  # - null (a load or member call through a null pointer): x86-64 faults on it and ASan's
  #   handler reports the fault with its stack; a check on every pointer Eigen dereferences;
  # - alignment (a misaligned load): x86-64 loads any alignment, and the aligned SSE/AVX loads
  #   Eigen emits fault on a misaligned address, which ASan reports as above.
  add_compile_options(-fsanitize=address,undefined
                      -fno-sanitize=object-size,pointer-overflow,null,alignment
                      -fno-omit-frame-pointer -fno-sanitize-recover=undefined)
  add_link_options(-fsanitize=address,undefined)
endif()

if(TORSION_TSAN)
  if(TORSION_SANITIZE)
    message(FATAL_ERROR "TORSION_TSAN and TORSION_SANITIZE cannot be combined (ThreadSanitizer "
                        "excludes AddressSanitizer): configure two build directories")
  endif()
  if(NOT CMAKE_CXX_COMPILER_ID MATCHES "GNU|Clang")
    message(FATAL_ERROR "TORSION_TSAN needs GCC or Clang")
  endif()
  add_compile_options(-fsanitize=thread -fno-omit-frame-pointer)
  add_link_options(-fsanitize=thread)
endif()
