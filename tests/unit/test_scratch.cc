// The test files' lifetime (tests/support/scratch.h): a passing test run removes its scratch
// directories, a failing one keeps them and names them. Checked by running this executable's own
// hidden cases, one that passes and one that fails, as child processes.
#include <filesystem>
#include <fstream>
#include <iostream>
#include <string>

#include <catch2/catch.hpp>

#include "tests/support/run_program.h"
#include "tests/support/scratch.h"

namespace {

/// Runs this executable with a test spec.
nimble::test::RigResult run_self(const std::string& spec) {
  const std::string self = std::filesystem::read_symlink("/proc/self/exe").string();
  return nimble::test::run_program("'" + self + "'", "'" + spec + "'", "RIG_KEEP_TEST_FILES=");
}

/// The directory a child printed as "scratch: <path>".
std::string printed_dir(const std::string& out) {
  const auto at = out.find("scratch: ");
  if (at == std::string::npos) return "";
  return out.substr(at + 9, out.find('\n', at) - at - 9);
}

void fill(const std::string& dir) {
  std::ofstream(dir + "/data.txt") << "recorded\n";
  std::cout << "scratch: " << dir << std::endl;
}

}  // namespace

TEST_CASE("scratch probe that passes", "[.scratch_pass]") {
  fill(nimble::test::scratch_dir("scratch_probe"));
  CHECK(true);
}

TEST_CASE("scratch probe that fails", "[.scratch_fail]") {
  fill(nimble::test::scratch_dir("scratch_probe"));
  CHECK(1 + 1 == 3);
}

TEST_CASE("test files: a passing test's scratch directory is removed at its end, a failing test's is kept and named",
          "[scratch]") {
  const auto pass = run_self("[.scratch_pass]");
  INFO(pass.out << pass.err);
  REQUIRE(pass.exit_code == 0);
  const std::string pass_dir = printed_dir(pass.out);
  REQUIRE(!pass_dir.empty());
  CHECK(!std::filesystem::exists(pass_dir));

  const auto fail = run_self("[.scratch_fail]");
  INFO(fail.out << fail.err);
  CHECK(fail.exit_code != 0);
  const std::string fail_dir = printed_dir(fail.out);
  REQUIRE(!fail_dir.empty());
  CHECK(std::filesystem::exists(fail_dir + "/data.txt"));
  CHECK(fail.err.find("test files kept in " + fail_dir) != std::string::npos);
  std::filesystem::remove_all(fail_dir);
}
