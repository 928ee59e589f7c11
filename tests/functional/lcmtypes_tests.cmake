# Functional tests of the LCM message contract (lcmtypes/). Included from tests/CMakeLists.txt,
# which provides the rig_catch_main library and rig_discover_tests (cmake/RigTests.cmake).
add_executable(test_lcmtypes ${CMAKE_CURRENT_LIST_DIR}/test_lcmtypes.cc)
target_link_libraries(test_lcmtypes PRIVATE rig_catch_main nimble_contract nimble_lcmtypes PkgConfig::LCM)
rig_discover_tests(test_lcmtypes PREFIX "functional.lcmtypes." LABELS functional)

# Java and C++ fingerprints of the same types (lcm-spy decodes with the Java ones).
set(_fp_classes ${CMAKE_CURRENT_BINARY_DIR}/fingerprint_classes)
add_custom_command(
  OUTPUT ${_fp_classes}/PrintFingerprints.class
  COMMAND ${CMAKE_COMMAND} -E make_directory ${_fp_classes}
  COMMAND ${Java_JAVAC_EXECUTABLE} -d ${_fp_classes} ${CMAKE_CURRENT_LIST_DIR}/PrintFingerprints.java
  DEPENDS ${CMAKE_CURRENT_LIST_DIR}/PrintFingerprints.java
  COMMENT "Compiling PrintFingerprints.java")
add_custom_target(fingerprint_classes DEPENDS ${_fp_classes}/PrintFingerprints.class)
add_executable(test_java_fingerprints ${CMAKE_CURRENT_LIST_DIR}/test_java_fingerprints.cc)
target_link_libraries(test_java_fingerprints PRIVATE rig_catch_main nimble_lcmtypes)
get_target_property(_types_jar nimble_lcmtypes_jar JAR_FILE)
target_compile_definitions(test_java_fingerprints PRIVATE
  JAVA_EXE="${Java_JAVA_EXECUTABLE}"
  FINGERPRINT_CLASSES="${_fp_classes}"
  TYPES_JAR="${_types_jar}"
  LCM_JAR="${LCM_JAVA_JAR}")
add_dependencies(test_java_fingerprints fingerprint_classes nimble_lcmtypes_jar)
rig_discover_tests(test_java_fingerprints PREFIX "functional.lcmtypes." LABELS functional)

# The plant, controller, estimator and motion-capture processes' nodes on memq:// (one process,
# no network).
add_executable(test_process_nodes ${CMAKE_CURRENT_LIST_DIR}/test_process_nodes.cc)
target_link_libraries(test_process_nodes PRIVATE rig_catch_main nimble_plant_node nimble_controller_node
  nimble_estimator_node nimble_mocap_node)
target_compile_definitions(test_process_nodes PRIVATE RIG_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
rig_discover_tests(test_process_nodes PREFIX "functional.process." LABELS functional)

# The owner of the message contract (contract/): channel table and nominal rates.
add_executable(test_contract ${CMAKE_CURRENT_LIST_DIR}/test_contract.cc)
target_link_libraries(test_contract PRIVATE rig_catch_main nimble_contract nimble_lcmtypes)
target_compile_definitions(test_contract PRIVATE RIG_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
rig_discover_tests(test_contract PREFIX "functional.contract." LABELS functional)

# The launcher's run monitor reading the contract's messages (lateness of poses, drops, malformed).
add_executable(test_run_monitor ${CMAKE_CURRENT_LIST_DIR}/test_run_monitor.cc)
target_link_libraries(test_run_monitor PRIVATE rig_catch_main nimble_launcher)
rig_discover_tests(test_run_monitor PREFIX "functional.monitor." LABELS functional)

add_executable(test_messages ${CMAKE_CURRENT_LIST_DIR}/test_messages.cc)
target_link_libraries(test_messages PRIVATE rig_catch_main nimble_messages)
rig_discover_tests(test_messages PREFIX "functional.messages." LABELS functional)

# The one list of message types (nimble/rig_message_list.hpp): every .lcm file in it, in the
# viewers' types and in the fuzz targets' (fuzz/fuzz_support.cc, built here without libFuzzer);
# every channel's type listed, every type on a channel, every periodic channel with its rate.
add_executable(test_message_list ${CMAKE_CURRENT_LIST_DIR}/test_message_list.cc ${PROJECT_SOURCE_DIR}/fuzz/fuzz_support.cc)
target_link_libraries(test_message_list PRIVATE rig_catch_main nimble_lcmjson nimble_contract nimble_lcmtypes)
target_include_directories(test_message_list PRIVATE ${PROJECT_SOURCE_DIR})
target_compile_definitions(test_message_list PRIVATE RIG_SOURCE_DIR="${PROJECT_SOURCE_DIR}")
rig_discover_tests(test_message_list PREFIX "functional.message_list." LABELS functional)
