# rig_discover_tests(<target> PREFIX <prefix> LABELS <label> [TIMEOUT <s>] [TEST_SPEC <spec>])
#
# Registers every Catch2 test case of <target> as its own CTest entry, as catch_discover_tests
# does, and makes an entry that runs no test case fail: Catch2's `--warn NoTests` turns "No test
# cases matched" into exit status 2. The test `meta.ctest_entries` (tests/meta) checks, after the
# build, that every discovered entry selects exactly one test case; a `;` in a test name is the
# usual cause of an entry that selects none (CTest splits the name in two). TEST_SPEC registers
# only the test cases it selects (e.g. "[records]" or "~[records]"), so one executable's cases
# may carry different labels.
include(Catch)

function(rig_discover_tests target)
  cmake_parse_arguments(ARG "" "PREFIX;LABELS;TIMEOUT;TEST_SPEC" "" ${ARGN})
  if(NOT ARG_PREFIX OR NOT ARG_LABELS)
    message(FATAL_ERROR "rig_discover_tests(${target}): PREFIX and LABELS are required")
  endif()
  set(properties LABELS ${ARG_LABELS})
  if(ARG_TIMEOUT)
    list(APPEND properties TIMEOUT ${ARG_TIMEOUT})
  endif()
  set(spec "")
  if(ARG_TEST_SPEC)
    set(spec TEST_SPEC "${ARG_TEST_SPEC}")
  endif()
  catch_discover_tests(${target}
    ${spec}
    TEST_PREFIX "${ARG_PREFIX}"
    EXTRA_ARGS --warn NoTests
    PROPERTIES ${properties})
endfunction()
