// Scenario loading (scenario/scenario.h): which values are file paths.

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "scenario/scenario.h"

namespace fs = std::filesystem;

namespace {

/// A scratch folder with a scenario that uses a section base and path-like keys inside sections.
fs::path write_tree() {
  const fs::path dir = fs::temp_directory_path() / ("rig_scenario_tree_" + std::to_string(::getpid()));
  fs::create_directories(dir / "sub");
  std::ofstream(dir / "sub" / "plant_base.yaml") << "rate_hz: 1000\n"
                                                    "effects:\n"
                                                    "  lateral_gust:\n"
                                                    "    model: gauss_markov\n";
  std::ofstream(dir / "scenario.yaml") << "model: models/m.yaml\n"
                                          "manoeuvre: manoeuvres/x.yaml\n"
                                          "plant:\n"
                                          "  base: sub/plant_base.yaml\n"
                                          "  vehicle: not_a_path\n";
  return dir;
}

}  // namespace

TEST_CASE("scenario tree: top-level files and base are paths relative to their file, section keys of the same name "
          "are values",
          "[scenario]") {
  const fs::path dir = write_tree();
  const YAML::Node t = nimble::load_scenario_tree((dir / "scenario.yaml").string());
  CHECK(t["model"].as<std::string>() == (dir / "models/m.yaml").lexically_normal().string());
  CHECK(t["manoeuvre"].as<std::string>() == (dir / "manoeuvres/x.yaml").lexically_normal().string());
  // The section's base was found relative to the scenario and merged in.
  CHECK(t["plant"]["rate_hz"].as<int>() == 1000);
  CHECK_FALSE(t["plant"]["base"]);
  // Keys inside sections that share a top-level path key's name stay as written.
  CHECK(t["plant"]["effects"]["lateral_gust"]["model"].as<std::string>() == "gauss_markov");
  CHECK(t["plant"]["vehicle"].as<std::string>() == "not_a_path");
  fs::remove_all(dir);
}

TEST_CASE("scenario: a top-level section that no process reads is refused, naming it", "[scenario]") {
  // EKF settings belong under sensing.ekf; a top-level estimator section would be ignored.
  YAML::Node t = YAML::Load("name: t\nduration_s: 1\nclock: lockstep\nseed: 1\nprocesses: [plant]\n");
  t["model"] = std::string(RIG_SOURCE_DIR) + "/rig_configs/models/nimble_lateral_set1.yaml";
  nimble::scenario_from_tree(t, "t.yaml");  // valid as it stands
  t["estimator"]["history_s"] = 5;
  try {
    nimble::scenario_from_tree(t, "t.yaml");
    FAIL("a top-level estimator section was accepted");
  } catch (const nimble::ConfigError& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find("estimator") != std::string::npos);
    CHECK(std::string(e.what()).find("unknown key") != std::string::npos);
  }
}
