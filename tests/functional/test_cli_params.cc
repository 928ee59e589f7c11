// Functional tests of `rig params` and of the parameter tables against the shipped sensing
// base: the tables the loader and the validation use are the documentation, and every key of
// them is written, at its default, in rig_configs/sensing/default_sensing.yaml.

#include <sys/wait.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <type_traits>
#include <variant>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "estimator/ekf.h"
#include "estimator/imu_prefilter.h"
#include "plant/plant_model.h"
#include "sensors/sensor_config.h"

namespace {

struct Out {
  int code = -1;
  std::string text;
};

Out rig(const std::string& args) {
  const std::string cmd = std::string(RIG_BIN) + " " + args + " 2>&1";
  Out o;
  FILE* p = ::popen(cmd.c_str(), "r");
  REQUIRE(p != nullptr);
  char buf[4096];
  std::size_t n = 0;
  while ((n = std::fread(buf, 1, sizeof buf, p)) > 0) o.text.append(buf, n);
  const int status = ::pclose(p);
  o.code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return o;
}

template <typename Config>
void check_documented(const nimble::ParamTable<Config>& table, const Config& defaults, const YAML::Node& section,
                      const std::string& name) {
  for (const auto& p : table) {
    INFO(name << "." << p.key);
    // A key group.name lives in the sub-mapping group (e.g. imu.gyro_misalignment_rad.xy).
    const auto dot = p.key.find('.');
    const YAML::Node at = dot == std::string::npos ? section : YAML::Node(section[p.key.substr(0, dot)]);
    const std::string key = dot == std::string::npos ? p.key : p.key.substr(dot + 1);
    REQUIRE(at[key]);
    // The shipped base writes each default (to its printed precision).
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(defaults.*member)>;
          if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
            for (int i = 0; i < 3; ++i) {
              const char* axis = nimble::kXyzAxes[static_cast<std::size_t>(i)];
              CHECK(at[key][axis].template as<double>() == Approx((defaults.*member)[i]).epsilon(1e-4).margin(1e-12));
            }
          } else if constexpr (std::is_same_v<T, bool>) {
            CHECK(at[key].template as<bool>() == defaults.*member);
          } else {
            CHECK(at[key].template as<double>() ==
                  Approx(static_cast<double>(defaults.*member)).epsilon(1e-4).margin(1e-12));
          }
        },
        p.member);
  }
}

}  // namespace

TEST_CASE("rig params prints each section's table, and an unknown section is named", "[cli]") {
  const Out all = rig("params");
  REQUIRE(all.code == 0);
  for (const char* key : {"`run.stop_grace_s`", "`run.spin_us`", "`lockstep.ack_timeout_ms`", "`summary.max_phi_deg`",
                          "`sensing.imu.gyro_noise_sigma_radps`", "`sensing.mocap.latency_us`",
                          "`sensing.ekf.measurement_noise.attitude_var_rad2`", "`plant.thrust.slope_n_per_hz`",
                          "`plant.command_resolution.flap_freq_radps`", "`controller.mixing.roll_cmd_to_delta_f_radps`",
                          "`can_bridge.health_rate_hz`"}) {
    CHECK(all.text.find(key) != std::string::npos);
  }
  const Out mocap = rig("params sensing.mocap");
  REQUIRE(mocap.code == 0);
  CHECK(mocap.text.find("| `sensing.mocap.latency_us` | 5000 | in [0, 1e+06] | us |") != std::string::npos);
  CHECK(mocap.text.find("sensing.imu") == std::string::npos);
  const Out bad = rig("params sensing.lidar");
  CHECK(bad.code == 2);
  CHECK(bad.text.find("sensing.lidar") != std::string::npos);
  CHECK(bad.text.find("sensing.imu") != std::string::npos);  // the sections there are
}

TEST_CASE("every tabled sensing parameter is written at its default in the shipped sensing base", "[cli]") {
  const YAML::Node base = YAML::LoadFile(std::string(RIG_SOURCE_DIR) + "/rig_configs/sensing/default_sensing.yaml");
  check_documented(nimble::imu_params(), nimble::ImuModelConfig{}, base["imu"], "imu");
  check_documented(nimble::mocap_params(), nimble::MocapConfig{}, base["mocap"], "mocap");
  check_documented(nimble::imu_prefilter_params(), nimble::ImuPrefilterConfig{}, base["imu_prefilter"],
                   "imu_prefilter");
  // The EKF's keys live in sub-mappings (process_noise.gyro_var_per_sample_rad2ps2 ...).
  const YAML::Node ekf = base["ekf"];
  for (const auto& p : nimble::ekf_params()) {
    INFO("ekf." << p.key);
    YAML::Node node = YAML::Clone(ekf);
    std::string rest = p.key;
    for (auto dot = rest.find('.'); dot != std::string::npos; dot = rest.find('.')) {
      node = YAML::Node(node[rest.substr(0, dot)]);
      REQUIRE(node);
      rest = rest.substr(dot + 1);
    }
    CHECK(node[rest]);
  }
}

TEST_CASE("every tabled plant parameter is written at its default in the shipped plant base", "[cli]") {
  const YAML::Node root = YAML::LoadFile(std::string(RIG_SOURCE_DIR) + "/rig_configs/plant/nimble_plant.yaml");
  const YAML::Node plant = root["plant"] ? root["plant"] : root;
  // The top-level keys, then each sub-mapping's (command_resolution.* is in plant_params()).
  for (const auto& p : nimble::plant::plant_params()) {
    INFO(p.key);
    const auto dot = p.key.find('.');
    const YAML::Node node =
        dot == std::string::npos ? plant[p.key] : plant[p.key.substr(0, dot)][p.key.substr(dot + 1)];
    REQUIRE(node);
    CHECK(node.as<double>() == Approx(static_cast<double>(nimble::plant::PlantConfig{}.*
                                                          std::get<double nimble::plant::PlantConfig::*>(p.member)))
                                   .epsilon(1e-4));
  }
  check_documented(nimble::plant::flap_actuator_params(), nimble::plant::FlapActuatorConfig{}, plant["flap_actuator"],
                   "flap_actuator");
  check_documented(nimble::plant::servo_params(), nimble::plant::ServoConfig{}, plant["servo"], "servo");
  check_documented(nimble::plant::thrust_params(), nimble::ThrustCurve{}, plant["thrust"], "thrust");
}

TEST_CASE("docs/configuration.md is the configuration reference the parameter tables give now", "[cli]") {
  // Generated from the tables, never edited by hand: a parameter added, renamed or given another
  // default or range without regenerating the page fails here.
  const Out page = rig("params --doc-page");
  REQUIRE(page.code == 0);
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/docs/configuration.md");
  REQUIRE(in);
  std::stringstream text;
  text << in.rdbuf();
  INFO(
      "docs/configuration.md is out of date: regenerate it with build/bin/rig params --doc-page > "
      "docs/configuration.md");
  CHECK(text.str() == page.text);
  CHECK(page.text.find("`plant.effects.lateral_inflow.Y_vv`") != std::string::npos);
}
