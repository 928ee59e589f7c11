#define CATCH_CONFIG_MAIN
#include <catch2/catch.hpp>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <set>
#include <string>

#include "support/scratch.h"

namespace nimble::test {
namespace {

/// The scratch directories this process named, and whether a test case failed.
struct ScratchDirs {
  std::set<std::filesystem::path> dirs;
  bool failed = false;
};

ScratchDirs& scratch_dirs() {
  static ScratchDirs s;
  return s;
}

/// Removes the scratch directories when the run ends without a failure; otherwise names them.
struct ScratchListener : Catch::TestEventListenerBase {
  using TestEventListenerBase::TestEventListenerBase;
  void testCaseEnded(const Catch::TestCaseStats& stats) override {
    if (stats.totals.assertions.failed > 0 || stats.totals.testCases.failed > 0) scratch_dirs().failed = true;
  }
  void testRunEnded(const Catch::TestRunStats& stats) override {
    ScratchDirs& s = scratch_dirs();
    const char* keep = std::getenv("RIG_KEEP_TEST_FILES");
    const bool kept = s.failed || stats.totals.assertions.failed > 0 || (keep != nullptr && std::string(keep) == "1");
    for (const auto& dir : s.dirs) {
      std::error_code ec;
      if (!std::filesystem::exists(dir, ec)) continue;
      if (kept) {
        std::fprintf(stderr, "test files kept in %s\n", dir.c_str());
      } else {
        std::filesystem::remove_all(dir, ec);
      }
    }
  }
};

std::filesystem::path named(const std::string& tag) {
  const std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("rig_" + tag + "_" + std::to_string(::getpid()));
  scratch_dirs().dirs.insert(dir);
  return dir;
}

}  // namespace

std::string scratch_path(const std::string& tag) { return named(tag).string(); }

std::string scratch_dir(const std::string& tag) {
  const std::filesystem::path dir = named(tag);
  std::filesystem::remove_all(dir);
  std::filesystem::create_directories(dir);
  return dir.string();
}

std::string scratch_file(const std::string& tag, const std::string& name) {
  const std::filesystem::path dir = named(tag);
  std::filesystem::create_directories(dir);
  return (dir / name).string();
}

}  // namespace nimble::test

using ScratchListener = nimble::test::ScratchListener;
CATCH_REGISTER_LISTENER(ScratchListener)
