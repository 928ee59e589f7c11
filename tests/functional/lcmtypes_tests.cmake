# Functional tests of the LCM message contract (lcmtypes/). Included from tests/CMakeLists.txt,
# which provides the rig_catch_main library and include(Catch) for catch_discover_tests.
add_executable(test_lcmtypes ${CMAKE_CURRENT_LIST_DIR}/test_lcmtypes.cc)
target_link_libraries(test_lcmtypes PRIVATE rig_catch_main nimble_lcmtypes PkgConfig::LCM)
catch_discover_tests(test_lcmtypes
  TEST_PREFIX "functional.lcmtypes."
  PROPERTIES LABELS functional)
