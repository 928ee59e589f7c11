#pragma once
/// Sensor bias: the constant in both equations that a biased rate gyro leaves, told from a
/// constant load by the kinematics (p against phi's derivative). The plant flies the same
/// moment and force as a constant load (a bias of the simulated IMU is sensing.imu's).

#include "effects/effect.h"

namespace nimble::effects {

/// The effect's name, which the data-compatibility stage gives the rate gyro's bias it finds.
inline const std::string kSensorBiasName = "sensor_bias";

/// The effect's definition and its mapping from a model (registry.h); it has no plant section.
Effect sensor_bias_effect();

}  // namespace nimble::effects
