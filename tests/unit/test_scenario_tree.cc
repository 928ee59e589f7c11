// Scenario loading (scenario/scenario.h): which values are file paths.

#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <catch2/catch.hpp>

#include "scenario/scenario.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;

namespace {

/// A scratch folder with a scenario that uses a section base and path-like keys inside sections.
fs::path write_tree() {
  const fs::path dir = nimble::test::scratch_dir("scenario_tree");
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

TEST_CASE(
    "scenario tree: top-level files and base are paths relative to their file, section keys of the same name "
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

TEST_CASE(
    "scenario: a model file name the file system refuses (a component over 255 bytes) is a ConfigError "
    "naming the key and the reason, not an escaping filesystem_error",
    "[scenario]") {
  YAML::Node t = YAML::Load("name: t\nduration_s: 1\nclock: lockstep\nseed: 1\nprocesses: [plant]\n");
  t["model"] = std::string(RIG_SOURCE_DIR) + "/rig_configs/models/" + std::string(300, 'a') + ".yaml";
  try {
    nimble::scenario_from_tree(t, "t.yaml");
    FAIL("a model name too long for the file system was accepted");
  } catch (const nimble::ConfigError& e) {
    INFO(e.what());
    CHECK(std::string(e.what()).find("model") != std::string::npos);
    CHECK(std::string(e.what()).find("cannot be looked up") != std::string::npos);
  }
  t["model"] = std::string(RIG_SOURCE_DIR) + "/rig_configs/models/absent.yaml";
  CHECK_THROWS_WITH(nimble::scenario_from_tree(t, "t.yaml"), Catch::Contains("file not found"));
}

TEST_CASE(
    "scenario tree: every key's origin is recorded (file and line, base files, --set), and an error is "
    "moved there",
    "[scenario]") {
  const fs::path dir = write_tree();
  nimble::KeyOrigins origins;
  nimble::load_scenario_tree((dir / "scenario.yaml").string(), {{"plant.rate_hz", "2000"}, {"run", "{spin_us: 5}"}},
                             &origins);
  const std::string scenario = (dir / "scenario.yaml").string();
  const std::string base = (dir / "sub" / "plant_base.yaml").lexically_normal().string();
  // Keys of the scenario at their lines; keys of the base file at theirs, under the section.
  CHECK(origins.at("manoeuvre").file == scenario);
  CHECK(origins.at("manoeuvre").line == 2);
  CHECK(origins.at("plant.vehicle").line == 5);
  CHECK(origins.at("plant.effects.lateral_gust.model").line == 4);
  CHECK(fs::path(origins.at("plant.effects.lateral_gust.model").file).lexically_normal().string() == base);
  // What came from the command line, including the keys of a mapping given there.
  CHECK(origins.at("plant.rate_hz").file == "--set");
  CHECK(origins.at("run.spin_us").file == "--set");

  // An error about a key of the scenario is named where that key was written.
  const nimble::ConfigError in_base(scenario, "plant.effects.lateral_gust.model", "gauss_markov", "unknown model", 1);
  const nimble::ConfigError moved = nimble::locate_error(in_base, scenario, origins);
  CHECK(fs::path(moved.file()).lexically_normal().string() == base);
  CHECK(moved.line() == 4);
  CHECK(std::string(moved.what()).find("plant_base.yaml:4: key 'plant.effects.lateral_gust.model'") !=
        std::string::npos);
  const nimble::ConfigError from_set =
      nimble::locate_error(nimble::ConfigError(scenario, "plant.rate_hz", "2000", "too fast", 1), scenario, origins);
  CHECK(from_set.file() == "--set");
  CHECK(from_set.line() == -1);
  // A key below a recorded one takes the nearest recorded origin; another file's error stays.
  CHECK(nimble::locate_error(nimble::ConfigError(scenario, "plant.vehicle.x", "", "bad"), scenario, origins).line() ==
        5);
  // An entry of a list (plant.terms[0].expression) takes the list's origin: here --set.
  nimble::KeyOrigins with_terms;
  nimble::load_scenario_tree((dir / "scenario.yaml").string(), {{"plant.terms", "[{equation: L}]"}}, &with_terms);
  CHECK(nimble::locate_error(nimble::ConfigError(scenario, "plant.terms[0].expression", "p^", "bad", 1), scenario,
                             with_terms)
            .file() == "--set");
  CHECK(nimble::locate_error(nimble::ConfigError("model.yaml", "Lp", "", "bad", 7), scenario, origins).file() ==
        "model.yaml");
}

TEST_CASE("scenario tree: a base that is not a file name (a mapping, a list) is a ConfigError naming its key",
          "[scenario]") {
  // Found by fuzz_scenario_yaml: a mapping under plant.base escaped the loader as a yaml-cpp
  // conversion error instead of a ConfigError.
  const fs::path dir = nimble::test::scratch_dir("scenario_base");
  fs::create_directories(dir);
  for (const std::string& base : {std::string("\n    enabled: true\n"), std::string(" [a.yaml, b.yaml]\n")}) {
    INFO(base);
    std::ofstream(dir / "scenario.yaml") << "name: t\nplant:\n  base:" << base << "  rate_hz: 1000\n";
    try {
      nimble::load_scenario_tree((dir / "scenario.yaml").string());
      FAIL("a base that is not a file name was accepted");
    } catch (const nimble::ConfigError& e) {
      CHECK(std::string(e.what()).find("plant.base") != std::string::npos);
      CHECK(std::string(e.what()).find("must be the name of a base file") != std::string::npos);
    }
  }
  fs::remove_all(dir);
}

TEST_CASE("scenario digest: it covers the content of every file the scenario names, not only their paths",
          "[scenario]") {
  // A scenario in a scratch folder with its own copies of the model, the model's vehicle and the
  // manoeuvre, so that each can be changed under the same path.
  const fs::path dir = nimble::test::scratch_dir("scenario_digest");
  fs::create_directories(dir / "models");
  fs::create_directories(dir / "vehicles");
  const fs::path configs = fs::path(RIG_SOURCE_DIR) / "rig_configs";
  fs::copy_file(configs / "models" / "nimble_lateral_set1.yaml", dir / "models" / "m.yaml");
  fs::copy_file(configs / "vehicles" / "nimble_no_wifi.yaml", dir / "vehicles" / "nimble_no_wifi.yaml");
  fs::copy_file(configs / "manoeuvres" / "hover.yaml", dir / "hover.yaml");
  std::ofstream(dir / "scenario.yaml") << "name: d\nduration_s: 1\nclock: inprocess\nseed: 1\n"
                                          "processes: [plant, controller]\nmodel: models/m.yaml\n"
                                          "manoeuvre: hover.yaml\n";
  const auto digest = [&] { return nimble::scenario_digest(nimble::load_scenario((dir / "scenario.yaml").string())); };

  const auto files = nimble::named_files(nimble::load_scenario((dir / "scenario.yaml").string()));
  REQUIRE(files.size() == 3);
  CHECK(files[0].first == "model");
  CHECK(files[1].first == "model.vehicle");
  CHECK(files[1].second == (dir / "vehicles" / "nimble_no_wifi.yaml").string());
  CHECK(files[2].first == "manoeuvre");

  const std::string original = digest();
  CHECK(original.size() == 16);
  CHECK(digest() == original);  // nothing changed: the same digest
  // Each named file changed under its own path changes the digest.
  for (const fs::path& file :
       {dir / "models" / "m.yaml", dir / "vehicles" / "nimble_no_wifi.yaml", dir / "hover.yaml"}) {
    INFO(file);
    std::ofstream(file, std::ios::app) << "# changed\n";
    const std::string changed = digest();
    CHECK(changed != original);
    CHECK(changed.size() == 16);
  }
  fs::remove_all(dir);
}

TEST_CASE(
    "scenario tree: --set sensing.base=FILE stands the section on another base file (the flight vibration "
    "file) below which the default's other keys stay (without it: the scenario's own base)",
    "[scenario]") {
  const std::string configs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
  const std::string vibration = configs + "sensing/nimble_flight_vibration.yaml";
  nimble::KeyOrigins origins;
  const YAML::Node tree = nimble::load_scenario_tree(configs + "hover.yaml",
                                                     {nimble::parse_override("sensing.base=" + vibration)}, &origins);
  CHECK(tree["sensing"]["imu"]["structural_gyro_amplitude_radps"]["z"].as<double>() > 3.0);
  CHECK(tree["sensing"]["mocap"]["frame_rate_hz"].as<int>() == 200);  // from default_sensing.yaml below it
  CHECK_FALSE(tree["sensing"]["base"]);
  CHECK(origins.at("sensing.base").file == "--set");

  const YAML::Node plain = nimble::load_scenario_tree(configs + "hover.yaml");
  CHECK(plain["sensing"]["imu"]["structural_gyro_amplitude_radps"]["z"].as<double>() == 0.3);

  CHECK_THROWS_AS(nimble::load_scenario_tree(configs + "hover.yaml", {nimble::parse_override("sensing.base=")}),
                  nimble::ConfigError);
  CHECK_THROWS_AS(nimble::load_scenario_tree(configs + "hover.yaml",
                                             {nimble::parse_override("sensing.base=" + configs + "absent.yaml")}),
                  nimble::ConfigError);
}

TEST_CASE(
    "scenario tree: a scenario standing on another takes its sections as written, its own section base over "
    "the other's, and --set <section>.base reaches a section it inherits",
    "[scenario]") {
  const fs::path dir = nimble::test::scratch_dir("scenario_chain");
  std::ofstream(dir / "s1.yaml") << "a: 1\nb: 1\n";
  std::ofstream(dir / "s2.yaml") << "a: 2\n";
  std::ofstream(dir / "parent.yaml") << "sensing:\n  base: s1.yaml\n  extra: 5\n";
  std::ofstream(dir / "child.yaml") << "base: parent.yaml\nsensing:\n  base: s2.yaml\n";
  const YAML::Node child = nimble::load_scenario_tree((dir / "child.yaml").string());
  CHECK(child["sensing"]["a"].as<int>() == 2);      // the child's section base, not the parent's
  CHECK_FALSE(child["sensing"]["b"]);               // s1 is not below it
  CHECK(child["sensing"]["extra"].as<int>() == 5);  // the parent's own key of the section stays
  const YAML::Node parent = nimble::load_scenario_tree((dir / "parent.yaml").string());
  CHECK(parent["sensing"]["a"].as<int>() == 1);
  CHECK(parent["sensing"]["b"].as<int>() == 1);
  // A bad section base the other scenario wrote is named in that scenario's file.
  std::ofstream(dir / "bad_parent.yaml") << "sensing:\n  base: [s1.yaml]\n";
  std::ofstream(dir / "bad_child.yaml") << "base: bad_parent.yaml\n";
  nimble::KeyOrigins origins;
  try {
    nimble::load_scenario_tree((dir / "bad_child.yaml").string(), {}, &origins);
    FAIL("a list as a section's base was taken");
  } catch (const nimble::ConfigError& e) {
    CHECK(e.file() == (dir / "bad_parent.yaml").string());
    CHECK(e.key() == "sensing.base");
  }

  // The four-state scenario stands on the identification train, whose sensing section names the
  // default: --set sensing.base reaches it (it was merged under the default's keys, so lost).
  const std::string configs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
  const YAML::Node vib = nimble::load_scenario_tree(
      configs + "yaw_hold_lateral4.yaml",
      {nimble::parse_override("sensing.base=" + configs + "sensing/nimble_flight_vibration.yaml")});
  CHECK(vib["sensing"]["imu"]["structural_gyro_amplitude_radps"]["z"].as<double>() > 3.0);
  CHECK(vib["controller"]["yaw"]["enabled"].as<bool>());
  const YAML::Node plain = nimble::load_scenario_tree(configs + "yaw_hold_lateral4.yaml");
  CHECK(plain["sensing"]["imu"]["structural_gyro_amplitude_radps"]["z"].as<double>() == 0.3);
}
