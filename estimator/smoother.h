#pragma once
/// Fixed-interval smoothing of a recorded flight: the states as a lab makes them offline, from
/// the whole record of IMU and motion capture, for identification (thesis §3.5 and §4.1: the
/// identification data were made by fusing OptiTrack and on-board data after the flight, not by
/// an on-board real-time filter).
///
/// Forward pass: the rig's EKF (estimator/ekf.h) with the flight's own configuration, fed the
/// recorded IMU samples and motion-capture frames in time order as if each frame arrived at its
/// mid-exposure time (the offline data have no latency). A node is added at the time of every
/// measurement (the IMU input interpolated, as the filter does inside an interval), so that each
/// measurement is applied at a node and the recursion below is exact for the filter's model.
/// Backward pass (Rauch-Tung-Striebel): for nodes k = N-1 .. 0,
///   x_k|N = x_k|k + C_k (x_k+1|N - x_k+1|k),   C_k = P_k|k Phi_k^T P_k+1|k^-1,
/// with x_k+1|k, P_k+1|k and Phi_k the filter's own prediction from node k to node k+1
/// (AttitudeVelocityEkf::predict_between) and angle differences wrapped into (-pi, pi].
/// The smoothed estimate at a time uses the data before and after it: no lag, and an error
/// below the filter's.
///
/// Output: one sample per recorded IMU sample (the added nodes are left out), with the rate
/// p q r = gyro - smoothed gyro bias, as the real-time estimate reports it.
///
/// A flight whose IMU reads the flapping vibration and whose estimator filtered it on board
/// (sensing.imu_prefilter, estimator/imu_prefilter.h) is smoothed from the same filtering:
/// prefilter_imu() passes the recorded samples through an ImuPrefilter fed with the recorded
/// flapping frequencies (ACTUATOR_FB) as the estimator node feeds it, and its residual variance
/// per sample is the forward pass's input noise where it exceeds the configured one, as on board
/// (AttitudeVelocityEkf::predict's input_var_per_sample). The backward pass predicts each interval
/// with the input noise the forward pass used there (EkfNode::input_psd).

#include <cstdint>
#include <functional>
#include <vector>

#include <Eigen/Core>

#include "core/rig_values.h"
#include "estimator/ekf.h"
#include "estimator/imu_prefilter.h"
#include "estimator/mocap_measurement.h"

namespace nimble {

/// One smoothed sample.
struct SmoothedSample {
  std::int64_t utime = 0;                                ///< the IMU sample's time [us]
  EkfState x = EkfState::Zero();                         ///< smoothed state (ekf_model.h order)
  Eigen::Vector3d rate_radps = Eigen::Vector3d::Zero();  ///< gyro minus the smoothed gyro bias [rad/s]

  Eigen::Matrix<double, kEkfStateDim, 1> sigma = Eigen::Matrix<double, kEkfStateDim, 1>::Zero();  ///< 1-sigma of x
};

/// What the smoothing did.
struct SmootherReport {
  EkfCounters counters;           ///< the forward pass's filter counters
  std::int64_t measurements = 0;  ///< motion-capture measurements offered to the filter
  std::int64_t nodes = 0;         ///< nodes smoothed (IMU samples and measurement times)
};

/// Smooths a recorded flight (see the top of this header). `imu` and `poses` in time order as
/// recorded (poses by frame number); samples before the first motion-capture measurement are
/// not smoothed (the filter starts there). Returns an empty vector if there is no measurement.
/// `input_var` (optional, one per sample of `imu`): each sample's input noise as per-sample
/// variances [gyro (rad/s)^2, accelerometer (m/s^2)^2] at process_noise.reference_rate_hz; each
/// channel takes the larger of it and the configured one (PrefilteredImu::input_var).
/// @throws std::invalid_argument for an invalid configuration, or an `input_var` whose size is
///         not that of `imu`.
std::vector<SmoothedSample> smooth_flight(const EkfConfig& ekf, const VelocityDifferentiatorConfig& differentiator,
                                          const std::vector<ImuSample>& imu, const std::vector<MocapPose>& poses,
                                          SmootherReport* report = nullptr,
                                          const std::vector<EkfInput>* input_var = nullptr);

/// The wing pairs' measured flapping frequencies at a rig time (ACTUATOR_FB).
struct FlapFrequencies {
  std::int64_t utime = 0;  ///< rig time [us]
  double left_radps = 0.0;
  double right_radps = 0.0;
};

/// A recorded IMU through the on-board filtering.
struct PrefilteredImu {
  std::vector<ImuSample> imu;       ///< the filtered samples (stamps unchanged)
  std::vector<EkfInput> input_var;  ///< per sample: ImuPrefilter::residual_var() after it
};

/// The recorded samples `imu` (in the order recorded) through an ImuPrefilter of `config` at
/// `sample_rate_hz`, as the estimator node runs it (estimator/estimator_node.cc): before each
/// sample the prefilter is given every flapping frequency of `flaps` stamped at or before the
/// sample's rig time (`rig_utime` of its stamp; the identity if empty), in time order. Samples
/// with non-finite values are left out (the node does not use them), and so are those before the
/// prefilter has learnt its lines (ImuPrefilter::settled: the estimator starts its filter only
/// then; before, a sample still carries most of the vibration). Not enabled: the samples
/// unchanged and no input_var. @throws std::invalid_argument for an invalid configuration.
PrefilteredImu prefilter_imu(const ImuPrefilterConfig& config, double sample_rate_hz, const std::vector<ImuSample>& imu,
                             std::vector<FlapFrequencies> flaps,
                             const std::function<std::int64_t(std::int64_t)>& rig_utime = {});

}  // namespace nimble
