#pragma once
/// The smoother's model of a flight (ident/rig_log.h, SmoothingOptions) made from its sensing
/// configuration (estimator/sensing_config.h: load_sensing_config reads a sensing file). Library
/// nimble_ident_sensing (the rig's own: it needs the sensing configuration and the sensor models,
/// which the installed nimble_ident_lcm does not carry).

#include <string>

#include "estimator/sensing_config.h"
#include "ident/rig_log.h"

namespace nimble::ident {

/// The smoothing of a flight flown with `sensing`: its velocity differentiator, its on-board IMU
/// filtering (sensing.imu_prefilter), the IMU's rate and clock, and an EKF with the noise matched
/// to its sensors (ekf_config_matched_to_sensors): the vibration counted as white input noise
/// (smoother_ekf_config) when the IMU is not filtered, the white noise alone when it is (the
/// filter's residual variance is added per sample, as the estimator does on board).
SmoothingOptions smoothing_options(const SensingConfig& sensing);

}  // namespace nimble::ident
