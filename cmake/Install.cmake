# Install rules: `cmake --install build --prefix <dir>` puts the rig into a prefix.
#
#   bin/                          rig and the rig's processes (rig finds them next to itself)
#   lib/                          the libraries for reuse (static): nimble_core, nimble_contract,
#                                 nimble_messages, nimble_lcmlog, nimble_plots, nimble_ident,
#                                 nimble_ident_lcm, nimble_estimation
#   include/nimble_rig/           their headers (core/, contract/, lcmlog/, plots/, ident/, estimator/), the generated
#                                 LCM types (nimble/<type>.hpp) and their list (nimble/rig_message_list.hpp,
#                                 which contract/messages.h and contract/faults.cc include)
#   lib/cmake/nimble_rig/         find_package(nimble_rig): nimble_rig::lcmtypes, ::core,
#                                 ::contract, ::messages, ::lcmlog, ::plots, ::ident, ::ident_lcm,
#                                 ::estimation
#   lib/pkgconfig/nimble_rig.pc   the same for pkg-config
#   lib/python3/dist-packages/    nimble (the LCM types, generated) and nimble_rig (log reader)
#   share/java/                   nimble_lcmtypes.jar (lcm-spy, lcm-logplayer-gui)
#   share/nimble_rig/             the .lcm files, rig_configs/, the CAN DBC
include(GNUInstallDirs)
include(CMakePackageConfigHelpers)

set(NIMBLE_INSTALL_INCLUDEDIR "${CMAKE_INSTALL_INCLUDEDIR}/nimble_rig")
set(NIMBLE_INSTALL_CMAKEDIR "${CMAKE_INSTALL_LIBDIR}/cmake/nimble_rig")
# Debian's layout for Python modules outside the interpreter's own prefix.
set(NIMBLE_INSTALL_PYTHONDIR "lib/python3/dist-packages")

install(TARGETS rig nimble_plant nimble_controller nimble_estimator nimble_mocap nimble_can_bridge
        RUNTIME DESTINATION "${CMAKE_INSTALL_BINDIR}")

set(nimble_exported nimble_lcmtypes nimble_core nimble_contract nimble_messages nimble_lcmlog nimble_plots nimble_ident
    nimble_ident_lcm nimble_estimation)
set_target_properties(nimble_lcmtypes PROPERTIES EXPORT_NAME lcmtypes)
set_target_properties(nimble_core PROPERTIES EXPORT_NAME core)
set_target_properties(nimble_contract PROPERTIES EXPORT_NAME contract)
set_target_properties(nimble_messages PROPERTIES EXPORT_NAME messages)
set_target_properties(nimble_lcmlog PROPERTIES EXPORT_NAME lcmlog)
set_target_properties(nimble_plots PROPERTIES EXPORT_NAME plots)
set_target_properties(nimble_ident PROPERTIES EXPORT_NAME ident)
set_target_properties(nimble_ident_lcm PROPERTIES EXPORT_NAME ident_lcm)
set_target_properties(nimble_estimation PROPERTIES EXPORT_NAME estimation)
foreach(t IN LISTS nimble_exported)
  target_include_directories(${t} INTERFACE "$<INSTALL_INTERFACE:${NIMBLE_INSTALL_INCLUDEDIR}>")
endforeach()
install(TARGETS ${nimble_exported} EXPORT nimble_rigTargets
        ARCHIVE DESTINATION "${CMAKE_INSTALL_LIBDIR}")
install(EXPORT nimble_rigTargets NAMESPACE nimble_rig:: DESTINATION "${NIMBLE_INSTALL_CMAKEDIR}")

foreach(dir core contract lcmlog plots ident estimator)
  install(DIRECTORY "${PROJECT_SOURCE_DIR}/${dir}/" DESTINATION "${NIMBLE_INSTALL_INCLUDEDIR}/${dir}"
          FILES_MATCHING PATTERN "*.h")
endforeach()
install(DIRECTORY "${PROJECT_BINARY_DIR}/lcmtypes/nimble_lcmtypes_cpp/nimble"
        DESTINATION "${NIMBLE_INSTALL_INCLUDEDIR}")
install(FILES "${RIG_MESSAGE_LIST_DIR}/nimble/rig_message_list.hpp" DESTINATION "${NIMBLE_INSTALL_INCLUDEDIR}/nimble")

configure_package_config_file("${PROJECT_SOURCE_DIR}/cmake/nimble_rigConfig.cmake.in"
  "${PROJECT_BINARY_DIR}/nimble_rigConfig.cmake" INSTALL_DESTINATION "${NIMBLE_INSTALL_CMAKEDIR}")
write_basic_package_version_file("${PROJECT_BINARY_DIR}/nimble_rigConfigVersion.cmake"
  VERSION "${PROJECT_VERSION}" COMPATIBILITY SameMinorVersion)
install(FILES "${PROJECT_BINARY_DIR}/nimble_rigConfig.cmake" "${PROJECT_BINARY_DIR}/nimble_rigConfigVersion.cmake"
        DESTINATION "${NIMBLE_INSTALL_CMAKEDIR}")

configure_file("${PROJECT_SOURCE_DIR}/cmake/nimble_rig.pc.in" "${PROJECT_BINARY_DIR}/nimble_rig.pc" @ONLY)
install(FILES "${PROJECT_BINARY_DIR}/nimble_rig.pc" DESTINATION "${CMAKE_INSTALL_LIBDIR}/pkgconfig")

install(DIRECTORY "${PROJECT_BINARY_DIR}/python/nimble" DESTINATION "${NIMBLE_INSTALL_PYTHONDIR}")
configure_file("${PROJECT_SOURCE_DIR}/python/nimble_rig/__init__.py"
  "${PROJECT_BINARY_DIR}/python/nimble_rig/__init__.py" @ONLY)
foreach(f log.py live.py node.py participant.py _rig.pyi py.typed)
  configure_file("${PROJECT_SOURCE_DIR}/python/nimble_rig/${f}" "${PROJECT_BINARY_DIR}/python/nimble_rig/${f}" COPYONLY)
endforeach()
install(DIRECTORY "${PROJECT_BINARY_DIR}/python/nimble_rig" DESTINATION "${NIMBLE_INSTALL_PYTHONDIR}")

install(FILES "$<TARGET_PROPERTY:nimble_lcmtypes_jar,JAR_FILE>" DESTINATION "${CMAKE_INSTALL_DATADIR}/java")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/lcmtypes/" DESTINATION "${CMAKE_INSTALL_DATADIR}/nimble_rig/lcmtypes"
        FILES_MATCHING PATTERN "*.lcm")
install(DIRECTORY "${PROJECT_SOURCE_DIR}/rig_configs/" DESTINATION "${CMAKE_INSTALL_DATADIR}/nimble_rig/rig_configs")
install(FILES "${PROJECT_SOURCE_DIR}/can_bridge/nimble_rig.dbc" DESTINATION "${CMAKE_INSTALL_DATADIR}/nimble_rig")
