# rig_discover_tests(<target> PREFIX <prefix> LABELS <label>... [TIMEOUT <s>] [TEST_SPEC <spec>])
#
# Registers every Catch2 test case of <target> as its own CTest entry, as catch_discover_tests
# does, and makes an entry that runs no test case fail: Catch2's `--warn NoTests` turns "No test
# cases matched" into exit status 2. The test `meta.ctest_entries` (tests/meta) checks, after the
# build, that every discovered entry selects exactly one test case; a `;` in a test name is the
# usual cause of an entry that selects none (CTest splits the name in two). TEST_SPEC registers
# only the test cases it selects (e.g. "[records]" or "~[records]"), so one executable's cases
# may carry different labels. LABELS takes one label or several (`LABELS functional resource`):
# catch_discover_tests passes its properties on as a flat list, which cannot hold a list value,
# so several labels are set on the discovered entries by a CTest include file of their own, read
# after Catch2's (the entries' names come from its TEST_LIST variable).
include(Catch)

function(rig_discover_tests target)
  cmake_parse_arguments(ARG "" "PREFIX;TIMEOUT;TEST_SPEC" "LABELS" ${ARGN})
  if(NOT ARG_PREFIX OR NOT ARG_LABELS)
    message(FATAL_ERROR "rig_discover_tests(${target}): PREFIX and LABELS are required")
  endif()
  # The executables of each label: target sanitizer_pass builds those its labels run.
  foreach(label ${ARG_LABELS})
    set_property(GLOBAL APPEND PROPERTY RIG_TEST_TARGETS_${label} ${target})
  endforeach()
  list(GET ARG_LABELS 0 first_label)
  set(properties LABELS ${first_label})
  if(ARG_TIMEOUT)
    list(APPEND properties TIMEOUT ${ARG_TIMEOUT})
  endif()
  set(spec "")
  if(ARG_TEST_SPEC)
    set(spec TEST_SPEC "${ARG_TEST_SPEC}")
  endif()
  string(MAKE_C_IDENTIFIER "${target}_${ARG_PREFIX}_${ARG_TEST_SPEC}_tests" test_list)
  catch_discover_tests(${target}
    ${spec}
    TEST_PREFIX "${ARG_PREFIX}"
    TEST_LIST ${test_list}
    EXTRA_ARGS --warn NoTests
    PROPERTIES ${properties})
  list(LENGTH ARG_LABELS label_count)
  if(label_count GREATER 1)
    set(script "${CMAKE_CURRENT_BINARY_DIR}/${test_list}_labels.cmake")
    file(WRITE "${script}"
      "foreach(t IN LISTS ${test_list})\n"
      "  set_tests_properties(\"\${t}\" PROPERTIES LABELS \"${ARG_LABELS}\")\n"
      "endforeach()\n")
    set_property(DIRECTORY APPEND PROPERTY TEST_INCLUDE_FILES "${script}")
  endif()
endfunction()

# An entry that cannot run on this machine (a package missing): it fails, saying why, instead of
# vanishing from the suite.
function(rig_entry_not_run name why)
  add_test(NAME ${name} COMMAND ${CMAKE_COMMAND} -E echo "${name}: not run here: ${why}")
  set_tests_properties(${name} PROPERTIES PASS_REGULAR_EXPRESSION "^$")
endfunction()
