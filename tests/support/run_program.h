#pragma once
/// Test support: running a program and capturing what it printed (run_program), without
/// needing the rig (run_rig.h adds `rig` itself).

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

namespace nimble::test {

/// Exit code and captured output of one command.
struct RigResult {
  int exit_code = -1;
  std::string out;
  std::string err;
};

/// The whole content of a text file ("" if it cannot be read).
inline std::string slurp(const std::string& path) {
  std::ifstream in(path);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

/// Runs `[env] <program> <args>` through the shell, capturing stdout and stderr separately.
inline RigResult run_program(const std::string& program, const std::string& args, const std::string& env = "") {
  const auto dir = std::filesystem::temp_directory_path();
  const std::string tag = std::to_string(::getpid());
  const std::string out = (dir / ("rig_out_" + tag)).string();
  const std::string err = (dir / ("rig_err_" + tag)).string();
  const std::string cmd = env + (env.empty() ? "" : " ") + program + " " + args + " >" + out + " 2>" + err;
  const int status = std::system(cmd.c_str());
  RigResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  std::filesystem::remove(out);
  std::filesystem::remove(err);
  return r;
}

}  // namespace nimble::test
