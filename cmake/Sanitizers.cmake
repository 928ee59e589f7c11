# Sanitizer and fuzzing builds (clang only), chosen at configure time:
#
#   RIG_SANITIZE=ON  every target builds and links with AddressSanitizer and UndefinedBehaviorSanitizer;
#                    an undefined-behaviour report aborts the program (-fno-sanitize-recover), so a
#                    test that triggers one fails.
#   RIG_FUZZ=ON      adds fuzz/: one libFuzzer executable per input the rig reads (CTest label
#                    `fuzz`); the project's code is built with libFuzzer's coverage
#                    instrumentation (-fsanitize=fuzzer-no-link). Implies RIG_SANITIZE.
#
#   cmake -S . -B build-san -DCMAKE_CXX_COMPILER=clang++ -DRIG_SANITIZE=ON -DRIG_FUZZ=ON
#
# Debian bookworm: clang-14 (the compiler) and libclang-rt-14-dev (the ASan, UBSan and libFuzzer
# runtimes). The system's libraries (liblcm, yaml-cpp) are not instrumented.
option(RIG_SANITIZE "Build with AddressSanitizer and UndefinedBehaviorSanitizer (clang)" OFF)
option(RIG_FUZZ "Build the libFuzzer targets of fuzz/ (clang; implies RIG_SANITIZE)" OFF)

if(RIG_FUZZ)
  set(RIG_SANITIZE ON CACHE BOOL "Build with AddressSanitizer and UndefinedBehaviorSanitizer (clang)" FORCE)
endif()

if(RIG_SANITIZE)
  if(NOT CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
    message(FATAL_ERROR "RIG_SANITIZE/RIG_FUZZ need clang (-DCMAKE_CXX_COMPILER=clang++), not ${CMAKE_CXX_COMPILER_ID}")
  endif()
  # -O1 and line tables only: the build takes about half the time of -O2 -g, and reports still
  # name file and line.
  set(CMAKE_CXX_FLAGS_RELWITHDEBINFO "-O1 -gline-tables-only -DNDEBUG")
  set(RIG_SANITIZER_FLAGS -fsanitize=address,undefined -fno-sanitize-recover=undefined -fno-omit-frame-pointer)
  add_compile_options(${RIG_SANITIZER_FLAGS})
  add_link_options(${RIG_SANITIZER_FLAGS})
endif()

if(RIG_FUZZ)
  add_compile_options(-fsanitize=fuzzer-no-link)
endif()
