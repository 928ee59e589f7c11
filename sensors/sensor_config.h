#pragma once
/// Loading of the truth side of a scenario's `sensing` section (the emulated IMU and motion
/// capture) from YAML through the strict ConfigMap. The estimator's sections of the same mapping
/// (`velocity_differentiator`, `ekf`) and the check of the whole section are in
/// estimator/sensing_config.h.
///
/// Every key is optional and falls back to the struct default; unknown keys, non-numeric values
/// and out-of-range values are ConfigError naming file, key and value. 3-vectors are mappings with
/// keys x y z (sensor axes). rig_configs/sensing/default_sensing.yaml documents every key.

#include <cstdint>

#include "core/config.h"
#include "core/param_table.h"
#include "sensors/imu_model.h"
#include "sensors/mocap_emulator.h"

namespace nimble {

/// The sensor models of one scenario.
struct SensorConfig {
  ImuModelConfig imu;  ///< section `imu`
  MocapConfig mocap;   ///< section `mocap`
  /// Seed of the IMU and mocap noise generators of an offline run [-] (the processes seed
  /// from the scenario's seed).
  std::uint64_t seed = 1;
};

/// The `imu` section's scalar and vector parameters: key, range, unit, meaning (the defaults are
/// ImuModelConfig's). The loader, validate(ImuModelConfig) and `rig params` use this table; the
/// list `flapping_harmonics` is read and checked on its own.
const ParamTable<ImuModelConfig>& imu_params();
/// The `mocap` section's parameters (the defaults are MocapConfig's); the frame rate's whole
/// number of microseconds and the exposure within the frame are checked on their own.
const ParamTable<MocapConfig>& mocap_params();

/// Reads the `imu` section. @throws ConfigError.
ImuModelConfig imu_model_config_from(ConfigMap& map);
/// Reads the `mocap` section. @throws ConfigError.
MocapConfig mocap_config_from(ConfigMap& map);
/// Reads the optional seed and sections imu and mocap of a sensing mapping. Leaves the mapping's
/// other keys unread (no finish()): the estimator's sections and the strict check of the whole
/// mapping belong to sensing_config_from() (estimator/sensing_config.h). @throws ConfigError.
SensorConfig sensor_config_from(ConfigMap& map);

}  // namespace nimble
