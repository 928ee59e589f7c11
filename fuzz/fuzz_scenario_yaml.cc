// Fuzz target: the scenario loader as `rig run` uses it before anything starts
// (launcher/run_plan.h, load_run_plan): the scenario file, its `base:` files, the models, the
// manoeuvre and every process's section. The input is written as a scenario file next to links
// to rig_configs/'s folders, so that the shipped scenarios' relative paths resolve. Bad text is
// a ConfigError; anything else is a finding.

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

#include "core/config.h"
#include "fuzz/fuzz_support.h"
#include "launcher/run_plan.h"

namespace {

/// scratch/configs/: a link to every folder of rig_configs/, and the scenario's path.
const std::string& scenario_path() {
  static const std::string path = [] {
    namespace fs = std::filesystem;
    const fs::path dir = fs::path(nimble::fuzz::scratch_dir()) / "configs";
    fs::create_directories(dir);
    for (const auto& e : fs::directory_iterator(nimble::fuzz::source_dir() + "/rig_configs")) {
      if (e.is_directory()) fs::create_directory_symlink(e.path(), dir / e.path().filename());
    }
    return (dir / "fuzz_scenario.yaml").string();
  }();
  return path;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string& file = scenario_path();
  nimble::fuzz::write_file(file, data, size);
  nimble::launcher::RunOptions options;
  options.scenario_file = file;
  options.progress = false;
  options.print_summary = false;
  try {
    const nimble::launcher::RunPlan plan = nimble::launcher::load_run_plan(options);
    nimble::fuzz::require(!plan.scenario.processes.empty(), "a run plan without processes loaded");
  } catch (const nimble::ConfigError&) {
    // the documented outcome of a bad scenario
  }
  return 0;
}
