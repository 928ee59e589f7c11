#pragma once
/// Loading of a scenario's whole `sensing` section (the sensor models of sensors/sensor_config.h,
/// the velocity differentiator, the EKF) from YAML through the strict ConfigMap, and EKF noise
/// matched to the emulated sensors.
///
/// Every key is optional and falls back to the struct default; unknown keys, non-numeric values
/// and out-of-range values are ConfigError naming file, key and value. 3-vectors are mappings with
/// keys x y z (sensor axes), phi theta psi (attitude) or u v w (body velocity).
/// rig_configs/sensing/default_sensing.yaml documents every key.

#include <cstdint>
#include <string>

#include "core/config.h"
#include "estimator/ekf.h"
#include "estimator/imu_prefilter.h"
#include "estimator/mocap_measurement.h"
#include "sensors/sensor_config.h"

namespace nimble {

/// All sensing parameters of one scenario: the sensor models (imu, mocap, seed of SensorConfig)
/// and the estimator's sections.
struct SensingConfig : SensorConfig {
  VelocityDifferentiatorConfig velocity_differentiator;  ///< section `velocity_differentiator`
  EkfConfig ekf;                                         ///< section `ekf`
  ImuPrefilterConfig imu_prefilter;                      ///< section `imu_prefilter` (the firmware's IMU filtering)
};

/// Reads the `velocity_differentiator` section. @throws ConfigError.
VelocityDifferentiatorConfig velocity_differentiator_config_from(ConfigMap& map);
/// Reads the `ekf` section. @throws ConfigError.
EkfConfig ekf_config_from(ConfigMap& map);
/// Reads a sensing mapping with optional sections imu, mocap (sensor_config_from()),
/// velocity_differentiator, ekf, imu_prefilter and an optional seed; any other key is an error. Also checks that the EKF's rollback history holds what a motion-capture
/// measurement needs when it arrives (ekf_history_needed_s). @throws ConfigError.
SensingConfig sensing_config_from(ConfigMap& map);

/// What the EKF's rollback history must hold when a motion-capture measurement arrives [s].
struct EkfHistoryNeed {
  double latency_s = 0.0;  ///< the mocap latency
  double jitter_s = 0.0;   ///< 3 sigma of its jitter
  double window_s = 0.0;   ///< the differentiator's window before the measurement's own time: the
                           ///< whole span with velocity_measurement window_mean (the offset needs
                           ///< the filter's trajectory from the window's start), half with instant
  double imu_s = 0.0;      ///< two IMU periods (applied at the next IMU sample; the node before
                           ///< the window's start must be kept)
  double clock_s = 0.0;    ///< the largest |IMU clock - motion-capture clock| over the flight
                           ///< (imu.clock_offset_s, and its drift over `duration_s`): a
                           ///< measurement looks that much older (or newer) to the filter,
                           ///< whose time is the IMU's stamps
  double total_s() const { return latency_s + jitter_s + window_s + imu_s + clock_s; }
};
/// `duration_s`: the flight's length, over which imu.clock_drift_ppm moves the IMU clock (0: the
/// offset alone).
EkfHistoryNeed ekf_history_need(const SensingConfig& config, double duration_s = 0.0);
/// Refuses an ekf.latency.history_s (rollback mode) shorter than ekf_history_need(config,
/// duration_s) with a ConfigError naming the key of `map` (the sensing mapping) and every part of
/// the need. sensing_config_from() checks with the offset alone, the estimator with its flight's
/// duration. @throws ConfigError.
void check_ekf_history(ConfigMap& map, const SensingConfig& config, double duration_s);

/// Shortest ekf.latency.history_s [s] with which no motion-capture measurement arrives too old:
/// ekf_history_need(config).total_s().
double ekf_history_needed_s(const SensingConfig& config);
/// Loads a sensing file (e.g. rig_configs/sensing/default_sensing.yaml) as a scenario's `sensing`
/// section reads it: the files its `base:` keys name merged under it (nimble_flight_vibration.yaml
/// stands on default_sensing.yaml). @throws ConfigError.
SensingConfig load_sensing_config(const std::string& file);

/// Options of ekf_config_matched_to_sensors().
struct MatchedNoiseOptions {
  /// Add the mean square of the vibration (sum of amplitude^2 / 2 per axis) to the white input
  /// noise. The vibration is not white, so this is an approximation (conservative for the
  /// attitude and velocity, whose errors integrate the vibration over less than one period).
  bool include_vibration = false;
  /// Speed used to account for the attitude noise in the rotation of the differentiated velocity
  /// into body axes [m/s]: adds speed^2 * mean(attitude variance) to each velocity variance.
  double rotation_speed_mps = 0.5;
};

/// Returns `base` with process and measurement noise and initial bias sigmas set from the sensor
/// models, so that the filter's noise model is the one that generates the data:
///   Q: per-sample gyro/accelerometer variance = noise sigma^2 (+ vibration mean square), reference
///      rate = IMU rate; bias random walks = the IMU model's;
///   R: attitude variance = mocap attitude sigma^2 per axis; velocity variance =
///      differentiated_velocity_sigma_mps(position sigma, span)^2 + rotation term;
///   initial bias sigmas = the IMU model's turn-on sigmas.
EkfConfig ekf_config_matched_to_sensors(const EkfConfig& base, const ImuModelConfig& imu, const MocapConfig& mocap,
                                        const VelocityDifferentiatorConfig& differentiator,
                                        const MatchedNoiseOptions& options = {});

/// The EKF of the offline smoother (estimator/smoother.h) for a flight flown with `sensing`: its
/// EKF with the process and measurement noise matched to the sensors that made the data
/// (ekf_config_matched_to_sensors, vibration included): offline the sensors are known, and the
/// thesis's Eq 8.2 Q, which over-bounds the real vehicle's vibration, would make the smoother
/// lean on the motion capture more than the emulated IMU deserves.
EkfConfig smoother_ekf_config(const SensingConfig& sensing);

}  // namespace nimble
