// System tests of the data-compatibility stage on rig-flown data (docs/discrepancy.md "Data
// compatibility"): the real processes fly the compatibility flight (rig_configs/compat_doublet_train.yaml)
// with the emulated IMU's own errors set in the sensing section, and rig discrepancy on the log's raw
// sensor channels (--states sensors: the gyro at the IMU's stamps, the attitude at the motion
// capture's) must find each error with the set value inside its interval, name nothing
// aerodynamic for them, and name nothing when no error is set. The model is set 1 with the exact
// kinematic terms, and the IMU's vibration is off, so that a flight without a sensor error is a
// null case (test_discrepancy_rig.cc says why).

#include <cmath>
#include <map>
#include <set>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/rig_runs.h"

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
const std::string kModel = kConfigs + "models/nimble_lateral_set1_kinematic.yaml";
/// No vibration, no pilot, no turn-on gyro bias (a random bias of 0.02 rad/s sigma that the stage
/// rightly finds): the flight's gyro has only the errors a case sets.
const std::string kClean =
    " --clock lockstep --set pilot.enabled=false --set sensing.imu.vibration_enabled=false"
    " --set sensing.imu.gyro_bias_turn_on_sigma_radps=0";

YAML::Node fly_and_check(const std::string& tag, const std::string& sets) {
  const std::string dir = nimble::test::scratch_dir("compatibility_" + tag);
  const auto run = nimble::test::rig_run(kConfigs + "compat_doublet_train.yaml", dir, "--seed 5" + kClean + sets);
  INFO(run.output);
  REQUIRE(run.exit_code == 0);
  const std::string json = dir + "/discrepancy.json";
  const auto r = nimble::test::run_rig("discrepancy " + dir + "/run.lcmlog --states sensors --model " + kModel +
                                       " --json " + json);
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  return YAML::LoadFile(json);
}

}  // namespace

TEST_CASE(
    "rig-flown: the IMU's scale factor, clock offset, clock drift and bias set in the sensing file are each "
    "found from the raw sensors with the set value inside its interval, and nothing else is named",
    "[system][compatibility]") {
  const double k = 0.08, offset = -0.025, drift = 800.0, bias = 0.04;
  const YAML::Node d =
      fly_and_check("errors", " --set sensing.imu.gyro_scale_factor.x=" + std::to_string(k) +
                                  " --set sensing.imu.clock_offset_s=" + std::to_string(offset) +
                                  " --set sensing.imu.clock_drift_ppm=" + std::to_string(drift) +
                                  " --set sensing.imu.gyro_bias_initial_radps.x=" + std::to_string(bias) +
                                  " --set sensing.ekf.latency.history_s=0.12");
  INFO(d["summary"].as<std::string>());
  // The offset the stage reports is the one at the middle of the rows it checked: the IMU stamps
  // rig time t as t + offset + drift t.
  const double t_mid = d["compatibility"][0]["t_mid_s"].as<double>();
  const std::map<std::string, double> truth{{"sensor_scale", k},
                                            {"time_offset", offset + 1e-6 * drift * t_mid},
                                            {"clock_drift", drift},
                                            {"sensor_bias", bias}};
  std::set<std::string> found;
  for (const auto& e : d["effects"]) {
    const std::string name = e["name"].as<std::string>();
    INFO(name);
    REQUIRE(truth.count(name));  // no aerodynamic name, no term
    CHECK(e["channel"].as<std::string>() == "p");
    CHECK(e["interval"][0].as<double>() <= truth.at(name));
    CHECK(truth.at(name) <= e["interval"][1].as<double>());
    found.insert(name);
  }
  CHECK(found.size() == 4);
}

TEST_CASE("rig-flown: with no sensor error set, the raw sensors name nothing", "[system][compatibility]") {
  const YAML::Node d = fly_and_check("none", "");
  INFO(d["summary"].as<std::string>());
  CHECK(d["effects"].size() == 0);
  CHECK(d["verdict"].as<std::string>() == "none");
  REQUIRE(d["compatibility"][0]["ran"].as<bool>());
  for (const auto& e : d["compatibility"][0]["errors"]) CHECK_FALSE(e["significant"].as<bool>());
}
