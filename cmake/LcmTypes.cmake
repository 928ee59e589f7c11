# LcmTypes.cmake -- generate C++ headers and a Java jar from LCM type definitions.
#
#   rig_add_lcm_types(<target>
#                     PACKAGE <pkg>
#                     FILES <file.lcm>...
#                     [JAR <jar_target> [JAR_NAME <name>]]
#                     [PYTHON <python_target>])
#
# Each .lcm file must hold exactly one struct, named like the file (foo_t.lcm -> struct foo_t),
# declared in `package <pkg>;`. This is checked at configure time.
#
# C++: `lcm-gen --cpp` runs at build time into <binary dir>/<target>_cpp and produces
#   <pkg>/<type>.hpp for every file, to whose decoders LcmDecodeChecks.cmake adds the length and
#   count checks lcm-gen 1.3.1 leaves out. <target> is an INTERFACE library that exposes that include
#   directory, links PkgConfig::LCM and makes its consumers wait for the generation step.
#   Use as: #include <nimble/truth_state_t.hpp>
#
# Java (only with JAR): `lcm-gen --java`, `javac -cp lcm.jar` and `jar` run at build time and
#   produce ${PROJECT_BINARY_DIR}/share/java/<name>.jar (<name> defaults to <target>). <jar_target>
#   is built by ALL; its JAR_FILE property holds the jar path. Requires a JDK (javac, jar) and
#   LCM's lcm.jar (cache variable LCM_JAVA_JAR).
#
# Python (only with PYTHON): `lcm-gen --python` runs at build time into
#   ${PROJECT_BINARY_DIR}/python/<pkg>/ (one module per type and an __init__.py importing them;
#   the generated modules need only the standard library). <python_target> is built by ALL; its
#   PYTHON_DIR property holds ${PROJECT_BINARY_DIR}/python.
#
# Every step deletes its output directory before generating, so removed or renamed types never
# leave stale files behind, and re-running gives the same result.
#
# Requires PkgConfig::LCM (pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm)) to exist.

include_guard(GLOBAL)

find_program(LCM_GEN_EXECUTABLE NAMES lcm-gen DOC "LCM type generator (lcm-gen)")
if(NOT LCM_GEN_EXECUTABLE)
  message(FATAL_ERROR "lcm-gen not found. Install LCM's code generator (Debian: liblcm-bin) "
                      "or set LCM_GEN_EXECUTABLE.")
endif()

function(rig_add_lcm_types target)
  cmake_parse_arguments(PARSE_ARGV 1 ARG "" "PACKAGE;JAR;JAR_NAME;PYTHON" "FILES")
  if(ARG_UNPARSED_ARGUMENTS)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): unknown arguments: ${ARG_UNPARSED_ARGUMENTS}")
  endif()
  if(NOT ARG_PACKAGE)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): PACKAGE is required")
  endif()
  if(NOT ARG_FILES)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): FILES is required")
  endif()
  if(ARG_JAR_NAME AND NOT ARG_JAR)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): JAR_NAME needs JAR")
  endif()
  if(NOT TARGET PkgConfig::LCM)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): target PkgConfig::LCM does not exist; call "
                        "pkg_check_modules(LCM REQUIRED IMPORTED_TARGET lcm) first")
  endif()

  string(REPLACE "." "/" pkg_dir "${ARG_PACKAGE}")
  string(REPLACE "." "\\." pkg_regex "${ARG_PACKAGE}")
  set(cpp_dir "${CMAKE_CURRENT_BINARY_DIR}/${target}_cpp")

  # Validate the inputs and derive the generated file names (sorted: stable command lines).
  set(lcm_files "")
  set(types "")
  foreach(file IN LISTS ARG_FILES)
    get_filename_component(file "${file}" ABSOLUTE BASE_DIR "${CMAKE_CURRENT_SOURCE_DIR}")
    if(NOT EXISTS "${file}")
      message(FATAL_ERROR "rig_add_lcm_types(${target}): ${file} does not exist")
    endif()
    get_filename_component(type "${file}" NAME_WE)
    if(type IN_LIST types)
      message(FATAL_ERROR "rig_add_lcm_types(${target}): type ${type} is listed twice")
    endif()
    file(READ "${file}" text)
    string(PREPEND text "\n")
    if(NOT text MATCHES "\n[ \t]*package[ \t]+${pkg_regex}[ \t]*;")
      message(FATAL_ERROR "rig_add_lcm_types(${target}): ${file} does not declare "
                          "`package ${ARG_PACKAGE};`")
    endif()
    if(NOT text MATCHES "\n[ \t]*struct[ \t]+${type}[ \t\r\n{]")
      message(FATAL_ERROR "rig_add_lcm_types(${target}): ${file} does not define `struct ${type}` "
                          "(one struct per file, named like the file)")
    endif()
    list(APPEND lcm_files "${file}")
    list(APPEND types "${type}")
  endforeach()
  list(SORT lcm_files)
  list(SORT types)

  set(headers "")
  foreach(type IN LISTS types)
    list(APPEND headers "${cpp_dir}/${pkg_dir}/${type}.hpp")
  endforeach()

  # --- C++ -----------------------------------------------------------------------------------
  # --cpp-std=c++11 makes int8/int16 constants `static constexpr` (implicitly inline in C++17),
  # so they can be bound to references without an out-of-class definition.
  add_custom_command(
    OUTPUT ${headers}
    COMMAND "${CMAKE_COMMAND}" -E rm -rf "${cpp_dir}"
    COMMAND "${CMAKE_COMMAND}" -E make_directory "${cpp_dir}"
    COMMAND "${LCM_GEN_EXECUTABLE}" --cpp --cpp-std=c++11 --cpp-hpath "${cpp_dir}" ${lcm_files}
    COMMAND "${CMAKE_COMMAND}" "-DDIR=${cpp_dir}/${pkg_dir}" -P "${CMAKE_CURRENT_FUNCTION_LIST_DIR}/LcmDecodeChecks.cmake"
    DEPENDS ${lcm_files} "${LCM_GEN_EXECUTABLE}" "${CMAKE_CURRENT_FUNCTION_LIST_DIR}/LcmDecodeChecks.cmake"
    COMMENT "lcm-gen (C++): ${ARG_PACKAGE} types for ${target}"
    VERBATIM)
  add_custom_target(${target}_gen ALL DEPENDS ${headers})

  add_library(${target} INTERFACE)
  # Dependencies of an INTERFACE library are followed transitively by its consumers.
  add_dependencies(${target} ${target}_gen)
  # SYSTEM: the generated code is clean under -Wall -Wextra -Wpedantic but not under stricter
  # flags (-Wold-style-cast, -Wconversion, -Wcast-qual, ...) that consumers may enable.
  target_include_directories(${target} SYSTEM INTERFACE "$<BUILD_INTERFACE:${cpp_dir}>")
  target_link_libraries(${target} INTERFACE PkgConfig::LCM)
  target_compile_features(${target} INTERFACE cxx_std_11)
  # LCM 1.3.1's generated decoders write doubles through int64_t pointers
  # (__double_decode_array -> __int64_t_decode_array). With strict aliasing the optimiser
  # may read a decoded array field before that write (seen at -O2: a value-initialised
  # message decoded to zeros). Every consumer of the types compiles without it.
  target_compile_options(${target} INTERFACE -fno-strict-aliasing)

  # --- Python --------------------------------------------------------------------------------
  if(ARG_PYTHON)
    set(py_root "${PROJECT_BINARY_DIR}/python")
    set(py_files "${py_root}/${pkg_dir}/__init__.py")
    foreach(type IN LISTS types)
      list(APPEND py_files "${py_root}/${pkg_dir}/${type}.py")
    endforeach()
    add_custom_command(
      OUTPUT ${py_files}
      COMMAND "${CMAKE_COMMAND}" -E rm -rf "${py_root}/${pkg_dir}"
      COMMAND "${CMAKE_COMMAND}" -E make_directory "${py_root}"
      COMMAND "${LCM_GEN_EXECUTABLE}" --python --ppath "${py_root}" ${lcm_files}
      DEPENDS ${lcm_files} "${LCM_GEN_EXECUTABLE}"
      COMMENT "lcm-gen (Python): ${ARG_PACKAGE} types in ${py_root}"
      VERBATIM)
    add_custom_target(${ARG_PYTHON} ALL DEPENDS ${py_files})
    set_target_properties(${ARG_PYTHON} PROPERTIES PYTHON_DIR "${py_root}")
  endif()

  if(NOT ARG_JAR)
    return()
  endif()

  # --- Java ----------------------------------------------------------------------------------
  find_package(Java COMPONENTS Development QUIET)
  if(NOT Java_Development_FOUND OR NOT Java_JAVAC_EXECUTABLE OR NOT Java_JAR_EXECUTABLE)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): a Java Development Kit (javac, jar) is "
                        "required to build ${ARG_JAR} but was not found. Install one (Debian: "
                        "default-jdk-headless) or point JAVA_HOME at it.")
  endif()
  find_file(LCM_JAVA_JAR NAMES lcm.jar
            HINTS "${LCM_PREFIX}/share/java"
            PATHS /usr/share/java /usr/local/share/java
            DOC "LCM Java runtime (lcm.jar)")
  if(NOT LCM_JAVA_JAR)
    message(FATAL_ERROR "rig_add_lcm_types(${target}): lcm.jar not found. Install LCM's Java "
                        "bindings (Debian: liblcm-java) or set LCM_JAVA_JAR.")
  endif()

  if(ARG_JAR_NAME)
    set(jar_name "${ARG_JAR_NAME}")
  else()
    set(jar_name "${target}")
  endif()
  set(jar_dir "${PROJECT_BINARY_DIR}/share/java")
  set(jar_file "${jar_dir}/${jar_name}.jar")
  set(java_dir "${CMAKE_CURRENT_BINARY_DIR}/${target}_java")
  set(java_src "${java_dir}/src")
  set(java_cls "${java_dir}/classes")

  set(java_sources "")
  set(java_classes "")
  set(jar_entries "")
  foreach(type IN LISTS types)
    list(APPEND java_sources "${java_src}/${pkg_dir}/${type}.java")
    list(APPEND java_classes "${java_cls}/${pkg_dir}/${type}.class")
    list(APPEND jar_entries -C "${java_cls}" "${pkg_dir}/${type}.class")
  endforeach()

  # Fixed entry timestamps (jar --date, JDK 17.0.3+) and an explicit entry order make the jar
  # byte-for-byte reproducible for a given JDK.
  execute_process(COMMAND "${Java_JAR_EXECUTABLE}" --help
                  OUTPUT_VARIABLE jar_help ERROR_VARIABLE jar_help RESULT_VARIABLE jar_rc)
  set(jar_date "")
  if(jar_rc EQUAL 0 AND jar_help MATCHES "--date")
    set(jar_date "--date=2000-01-01T00:00:00Z")
  endif()

  add_custom_command(
    OUTPUT "${jar_file}"
    BYPRODUCTS ${java_sources} ${java_classes}
    COMMAND "${CMAKE_COMMAND}" -E rm -rf "${java_dir}" "${jar_file}"
    COMMAND "${CMAKE_COMMAND}" -E make_directory "${java_src}" "${java_cls}" "${jar_dir}"
    COMMAND "${LCM_GEN_EXECUTABLE}" --java --jpath "${java_src}" ${lcm_files}
    COMMAND "${Java_JAVAC_EXECUTABLE}" -encoding UTF-8 -cp "${LCM_JAVA_JAR}" -d "${java_cls}"
            ${java_sources}
    COMMAND "${Java_JAR_EXECUTABLE}" --create --file "${jar_file}" ${jar_date} ${jar_entries}
    DEPENDS ${lcm_files} "${LCM_GEN_EXECUTABLE}" "${LCM_JAVA_JAR}"
    COMMENT "lcm-gen (Java) + javac + jar: ${jar_file}"
    VERBATIM)
  add_custom_target(${ARG_JAR} ALL DEPENDS "${jar_file}")
  set_target_properties(${ARG_JAR} PROPERTIES JAR_FILE "${jar_file}")
endfunction()
