#pragma once
// Shared helpers of the estimator tests: recorded sensor data of a truth trajectory and a loop that
// feeds them to an EKF with a chosen delivery delay of the mocap frames.

#include <cstdint>
#include <functional>
#include <vector>

#include "estimator/ekf.h"
#include "estimator/sensing_config.h"
#include "truth_trajectory.h"

namespace nimble::test {

/// IMU samples, the truth at each of them, and every mocap frame of one run.
struct RecordedData {
  std::vector<ImuSample> imu;
  std::vector<EkfState> truth_at_imu;  ///< [euler, v_body, gyro bias, accel bias]
  std::vector<MocapPose> frames;
};

/// Records `duration_s` of the sensing chain of `sensing` on `profile` (seeded by sensing.seed).
RecordedData record_data(const TruthProfile& profile, const SensingConfig& sensing, double duration_s);

/// Estimate minus truth with wrapped angles.
EkfState estimation_error(const EkfState& estimate, const EkfState& truth);

/// Feeds `data` to `ekf` (initialised here from the truth at t = 0 with zero biases and the config's
/// initial covariance): IMU samples at their times, each frame delivered `delay_us` after its
/// timestamp through a MocapMeasurementBuilder (at equal times the IMU sample goes first).
/// `frame_hook` may modify frames before the builder; `after_imu(k)` runs after IMU sample k.
void feed(AttitudeVelocityEkf& ekf, const RecordedData& data, std::int64_t delay_us,
          const VelocityDifferentiatorConfig& differentiator, const std::function<void(MocapPose&)>& frame_hook,
          const std::function<void(std::size_t)>& after_imu);

/// `c` with every replayed step linearised again: the exact replay (EkfConfig::replay_relinearise_*,
/// the default).
EkfConfig exact_replay(EkfConfig c);

/// `c` with a replay reusing linearisations within the tolerances EkfConfig names (0.02 rad,
/// 0.05 m/s, 0.05 rad/s).
EkfConfig reusing_replay(EkfConfig c);

}  // namespace nimble::test
