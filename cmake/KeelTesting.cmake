# Helpers every part of the tree uses to register its tests with CTest.
#
#   keel_add_gtest(TARGET t SOURCES a.cpp b.cpp LIBS keel_mission LABELS unit)
#     builds a GoogleTest executable and registers each of its tests.
#   keel_add_pytest(NAME n PATH tests/verify/test_x.py LABELS verify [TIMEOUT s])
#     runs one pytest file (or folder) with the project venv's Python.
#   keel_add_command_test(NAME n COMMAND ... LABELS spec [TIMEOUT s])
#     any other command whose exit code is the verdict.
#
# With KEEL_BUILD_TESTS off (a build of the libraries and binaries only, without GoogleTest)
# each of them does nothing, so the parts' CMakeLists.txt call them unconditionally; code
# that refers to a test target afterwards checks `if(TARGET ...)`.

# Tests that start real DDS participants across processes (clusters, the demo, trace
# validation of a real run) take turns: they would otherwise compete for the cores with
# each other's heartbeats (false failure declarations) and could meet on a DDS domain.
# They are started before the tests without a COST (CTest runs the costliest first): taking
# turns makes them the longest chain of `./keel test`, which must not start last.
function(keel_serialise_if_cluster name labels)
  if(labels MATCHES "cluster|demo")
    set_tests_properties(${name} PROPERTIES RESOURCE_LOCK keel_dds_processes COST 100)
  endif()
endfunction()

function(keel_add_gtest)
  if(NOT KEEL_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "TARGET" "SOURCES;LIBS;LABELS" ${ARGN})
  add_executable(${ARG_TARGET} ${ARG_SOURCES})
  target_link_libraries(${ARG_TARGET} PRIVATE ${ARG_LIBS} GTest::gtest GTest::gtest_main GTest::gmock keel_warnings)
  gtest_discover_tests(${ARG_TARGET}
    WORKING_DIRECTORY ${CMAKE_SOURCE_DIR}
    PROPERTIES LABELS "${ARG_LABELS}" ENVIRONMENT "KEEL_ROOT=${CMAKE_SOURCE_DIR};KEEL_BUILD_DIR=${CMAKE_BINARY_DIR}"
    DISCOVERY_TIMEOUT 60)
endfunction()

function(keel_add_pytest)
  if(NOT KEEL_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "NAME;PATH;TIMEOUT" "LABELS;ARGS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  add_test(NAME ${ARG_NAME}
    COMMAND ${KEEL_PYTHON} -m pytest -q -p no:cacheprovider ${CMAKE_SOURCE_DIR}/${ARG_PATH} ${ARG_ARGS}
    WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(${ARG_NAME} PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${ARG_TIMEOUT}
    ENVIRONMENT "KEEL_ROOT=${CMAKE_SOURCE_DIR};KEEL_BUILD_DIR=${CMAKE_BINARY_DIR};KEEL_TLC_JAR=${KEEL_TLC_JAR};PYTHONDONTWRITEBYTECODE=1")
  keel_serialise_if_cluster(${ARG_NAME} "${ARG_LABELS}")
endfunction()

function(keel_add_command_test)
  if(NOT KEEL_BUILD_TESTS)
    return()
  endif()
  cmake_parse_arguments(ARG "" "NAME;TIMEOUT;PASS_REGULAR_EXPRESSION;FAIL_REGULAR_EXPRESSION"
    "COMMAND;LABELS" ${ARGN})
  if(NOT ARG_TIMEOUT)
    set(ARG_TIMEOUT 600)
  endif()
  set(command ${ARG_COMMAND})
  if(ARG_PASS_REGULAR_EXPRESSION)
    # CTest ignores the exit code of a test judged by its output: the command's own exit
    # code is printed after it and any other than 0 fails the test, so a crash (a bare
    # signal) after the expected output is still a failure.
    # (Newlines, not semicolons, separate the shell's commands: a semicolon splits a CMake
    # list.)
    set(command sh -c "\"\$@\"\ncode=\$?\necho keel-test-exit: \$code\nexit \$code" keel-test
      ${ARG_COMMAND})
    if(ARG_FAIL_REGULAR_EXPRESSION)
      set(ARG_FAIL_REGULAR_EXPRESSION "${ARG_FAIL_REGULAR_EXPRESSION}|keel-test-exit: [1-9]")
    else()
      set(ARG_FAIL_REGULAR_EXPRESSION "keel-test-exit: [1-9]")
    endif()
  endif()
  add_test(NAME ${ARG_NAME} COMMAND ${command} WORKING_DIRECTORY ${CMAKE_SOURCE_DIR})
  set_tests_properties(${ARG_NAME} PROPERTIES LABELS "${ARG_LABELS}" TIMEOUT ${ARG_TIMEOUT}
    ENVIRONMENT "KEEL_ROOT=${CMAKE_SOURCE_DIR};KEEL_BUILD_DIR=${CMAKE_BINARY_DIR};KEEL_TLC_JAR=${KEEL_TLC_JAR}")
  # A test judged by its output: what it must print (with PASS_REGULAR_EXPRESSION its exit
  # code is ignored) and what it must not.
  if(ARG_PASS_REGULAR_EXPRESSION)
    set_tests_properties(${ARG_NAME} PROPERTIES PASS_REGULAR_EXPRESSION "${ARG_PASS_REGULAR_EXPRESSION}")
  endif()
  if(ARG_FAIL_REGULAR_EXPRESSION)
    set_tests_properties(${ARG_NAME} PROPERTIES FAIL_REGULAR_EXPRESSION "${ARG_FAIL_REGULAR_EXPRESSION}")
  endif()
  keel_serialise_if_cluster(${ARG_NAME} "${ARG_LABELS}")
endfunction()
