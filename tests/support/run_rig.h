#pragma once
/// Test support: running the `rig` executable (RIG_BIN, a compile definition) and reading
/// what it wrote.

#include <string>

#include "run_program.h"

namespace nimble::test {

/// Runs `[env] rig <args>` through the shell, capturing stdout and stderr separately.
inline RigResult run_rig(const std::string& args, const std::string& env = "") {
  return run_program(RIG_BIN, args, env);
}

}  // namespace nimble::test
