#include "launcher/scenario_check.h"

#include <cmath>
#include <optional>
#include <sstream>

#include "can_bridge/bridge_config.h"
#include "controller/attitude_controller.h"
#include "controller/manoeuvre.h"
#include "controller/pilot.h"
#include "estimator/sensing_config.h"
#include "plant/plant_node.h"

namespace nimble::launcher {
void validate_process_sections(const Scenario& s) {
  ConfigMap sensing = s.section("sensing");
  sensing_config_from(sensing);
  ConfigMap plant_section = s.section("plant");
  const plant::PlantConfig plant = plant::plant_config_from(plant_section);
  try {
    plant::plant_model_for(s, plant);
  } catch (const std::invalid_argument& e) {
    throw ConfigError(s.file, "model", s.model_file, e.what());
  }

  if (process_run_options(s).controller_input == "estimate" && !(s.runs("estimator") && s.runs("mocap"))) {
    throw ConfigError(s.file, "run.controller_input", "estimate",
                      "flying on the estimate needs the processes estimator and mocap");
  }
  if (s.actuator_link == "can" || s.has_section("can_bridge")) {
    ConfigMap section = s.section("can_bridge");
    can::can_bridge_config_from(section);
  }
  if (s.actuator_link == "can" && !s.runs("controller")) {
    throw ConfigError(s.file, "actuator_link", "can",
                      "the CAN link carries the controller's commands: it needs the process controller");
  }
  ConfigMap pilot_section = s.section("pilot");
  if (pilot_config_from(pilot_section).enabled && !s.runs("controller")) {
    throw ConfigError(s.file, "pilot.enabled", "true",
                      "the pilot flies the controller's throttle: it needs the process controller");
  }
  // Without the process mocap (ideal sensing) the pilot watches the TRUTH height; flying on the
  // estimate needs mocap anyway (checked above).
  if (s.runs("controller")) {
    ConfigMap section = s.section("controller");
    const ControllerConfig controller = controller_config_from(section);
    const Manoeuvre manoeuvre = load_manoeuvre(manoeuvre_file(s, true, "the controller plays a manoeuvre file"));
    check_gain_sets(manoeuvre, controller);
    // The plant reconstructs delta_t from the collective with the controller's map.
    if (std::fabs(plant.collective_radps_per_pct - controller.throttle_to_freq_radps_per_pct) >
        1e-6 * controller.throttle_to_freq_radps_per_pct) {
      std::ostringstream why;
      why << "must equal controller.throttle.throttle_to_freq_radps_per_pct ("
          << controller.throttle_to_freq_radps_per_pct << ") so that the plant's delta_t is the controller's";
      throw ConfigError(s.file, "plant.collective_radps_per_pct", std::to_string(plant.collective_radps_per_pct),
                        why.str());
    }
  }
}

ProcessRates process_rates(const Scenario& s) {
  ProcessRates r;
  ConfigMap plant_section = s.section("plant");
  const plant::PlantConfig plant = plant::plant_config_from(plant_section);
  r.plant_hz = plant.rate_hz;
  r.truth_hz = plant.truth_rate_hz;
  r.feedback_hz = plant.feedback_rate_hz;
  ConfigMap sensing = s.section("sensing");
  const SensingConfig sc = sensing_config_from(sensing);
  r.imu_hz = sc.imu.sample_rate_hz;
  if (s.runs("mocap")) r.mocap_hz = sc.mocap.frame_rate_hz;
  if (s.runs("estimator")) r.estimator_hz = sc.imu.sample_rate_hz;
  if (process_run_options(s).controller_input == "estimate" && !(s.runs("estimator") && s.runs("mocap"))) {
    throw ConfigError(s.file, "run.controller_input", "estimate",
                      "flying on the estimate needs the processes estimator and mocap");
  }
  if (s.runs("controller")) {
    ConfigMap section = s.section("controller");
    r.controller_hz = controller_config_from(section).rate_hz;
  }
  if (s.actuator_link == "can") {
    ConfigMap section = s.section("can_bridge");
    r.can_link = true;
    r.can_health_hz = can::can_bridge_config_from(section).health_rate_hz;
  }
  return r;
}

}  // namespace nimble::launcher
