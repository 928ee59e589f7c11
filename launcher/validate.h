#pragma once
/// Validation of a scenario's process sections before anything is started, with the
/// same loaders the processes use, so that a bad value is reported once, up front,
/// naming its file and key.

#include "scenario/scenario.h"

namespace nimble::launcher {

/// Rates the processes of a scenario will run at.
struct ProcessRates {
  double plant_hz = 0.0;
  double truth_hz = 0.0;
  double feedback_hz = 0.0;
  double imu_hz = 0.0;
  double controller_hz = 0.0;  ///< 0 if the scenario has no controller
  double mocap_hz = 0.0;       ///< 0 if the scenario has no motion-capture emulator
  double estimator_hz = 0.0;   ///< 0 if the scenario has no estimator
  bool can_link = false;       ///< actuator_link: can (the two sides of the CAN bridge run)
  double can_health_hz = 0.0;  ///< CAN_HEALTH rate of each side (wall clock)
};

/// Loads every section, model and manoeuvre the scenario's processes will load, and checks
/// that the plant and controller agree on shared assumptions.
/// @throws ConfigError naming the file, key and value.
void validate_process_sections(const Scenario& scenario);

/// The rates of a validated scenario.
ProcessRates process_rates(const Scenario& scenario);

}  // namespace nimble::launcher
