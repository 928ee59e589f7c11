#pragma once
/// Offline run of the whole sensing chain without transport, for tests and benchmarks:
/// truth trajectory -> ImuModel (512 Hz) and MocapEmulator (200 Hz, latency, dropouts) ->
/// MocapMeasurementBuilder -> AttitudeVelocityEkf, all events processed in time order.
///
/// Events: IMU sample at t_k = round(k 1e6 / imu rate) us; mocap capture at each frame's
/// mid-exposure time (truth at that instant); mocap delivery at its publish time (mid-exposure +
/// latency), when the frame goes through the builder and its measurements into the EKF. At equal
/// times: capture, then IMU, then delivery.

#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include <Eigen/Core>

#include "estimator/ekf.h"
#include "estimator/sensing_config.h"
#include "truth_trajectory.h"

namespace nimble {

/// Scenario of one offline run.
struct SensingRunConfig {
  TruthProfile profile;   ///< truth manoeuvre
  SensingConfig sensing;  ///< sensors and EKF (sensing.seed seeds the noise)
  /// Duration [s].
  double duration_s = 20.0;
  /// If true, the initial estimate is the truth plus a draw from the initial covariance (seeded by
  /// sensing.seed); otherwise the truth attitude and velocity with zero biases.
  bool perturb_initial_state = true;
  /// Scripted mocap occlusions [s, s): frames with mid-exposure inside are not tracked.
  std::vector<std::pair<double, double>> forced_dropouts_s;
  /// Called on every frame before the builder (e.g. to inject outliers); may modify the frame.
  std::function<void(MocapPose&)> pose_hook;
  /// Record every n-th IMU step [-].
  int record_every = 1;
};

/// Estimate against truth at one IMU instant.
struct SensingRecord {
  /// Time [us].
  std::int64_t utime = 0;
  /// True state (attitude, body velocity, IMU biases).
  EkfState truth = EkfState::Zero();
  /// Estimate minus truth, angles wrapped [rad, m/s, rad/s, m/s^2].
  EkfState error = EkfState::Zero();
  /// Square roots of the covariance diagonal.
  EkfState sigma = EkfState::Zero();
  /// Normalised estimation error squared e^T P^-1 e [-] (12 dof).
  double nees = 0.0;
};

/// Output of run_sensing_simulation().
struct SensingRunResult {
  std::vector<SensingRecord> records;           ///< every record_every-th IMU step
  std::vector<EkfUpdateRecord> updates;         ///< every gating decision
  EkfCounters counters;                         ///< EKF counters at the end
  std::int64_t frames = 0;                      ///< mocap frames produced
  std::int64_t frames_invalid = 0;              ///< frames with tracking_valid false
  std::int64_t velocity_measurements = 0;       ///< 6-dof measurements built
  std::int64_t attitude_only_measurements = 0;  ///< 3-dof measurements built
  std::vector<ImuSample> imu;                   ///< every IMU sample, as recorded
  std::vector<MocapPose> poses;                 ///< every frame delivered, as recorded (after pose_hook)
};

/// Runs one scenario. @throws std::invalid_argument for invalid configs (from the components).
SensingRunResult run_sensing_simulation(const SensingRunConfig& config);

}  // namespace nimble
