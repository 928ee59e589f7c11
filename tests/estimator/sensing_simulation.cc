#include "sensing_simulation.h"

#include <cmath>
#include <deque>
#include <limits>
#include <random>

#include <Eigen/Cholesky>

#include "core/attitude.h"
#include "estimator/mocap_measurement.h"

namespace nimble {
namespace {

EkfState true_state(const TruthSample& truth, const ImuModel& imu) {
  EkfState x;
  x << truth.euler_rad, truth.velocity_body_mps, imu.gyro_bias_radps(), imu.accel_bias_mps2();
  return x;
}

}  // namespace

SensingRunResult run_sensing_simulation(const SensingRunConfig& cfg) {
  const SensingConfig& s = cfg.sensing;
  TruthTrajectory truth(cfg.profile, 0);
  ImuModel imu(s.imu, s.seed);
  MocapEmulator mocap(s.mocap, s.seed + 1000003ULL);
  for (const auto& window : cfg.forced_dropouts_s) {
    mocap.add_forced_dropout(static_cast<std::int64_t>(std::llround(window.first * 1e6)),
                             static_cast<std::int64_t>(std::llround(window.second * 1e6)));
  }
  mocap.start_at(0);
  MocapMeasurementBuilder builder(s.velocity_differentiator);
  AttitudeVelocityEkf ekf(s.ekf);
  SensingRunResult result;
  ekf.set_update_observer([&result](const EkfUpdateRecord& r) { result.updates.push_back(r); });

  // Initial estimate.
  const TruthSample& t0 = truth.advance_to(0);
  const EkfCovariance P0 = s.ekf.initial_covariance();
  EkfState x0 = true_state(t0, imu);
  if (cfg.perturb_initial_state) {
    std::mt19937_64 rng(s.seed + 77ULL);
    std::normal_distribution<double> normal(0.0, 1.0);
    EkfState n;
    for (int i = 0; i < kEkfStateDim; ++i) n[i] = normal(rng);
    x0 += Eigen::LLT<EkfCovariance>(P0).matrixL() * n;
  } else {
    x0.tail<6>().setZero();
  }
  ekf.initialize(0, x0, P0);

  const std::int64_t end_utime = static_cast<std::int64_t>(std::llround(cfg.duration_s * 1e6));
  const double imu_period_us = 1e6 / s.imu.sample_rate_hz;
  std::int64_t imu_index = 0;
  std::deque<MocapPose> in_flight;
  const std::int64_t never = std::numeric_limits<std::int64_t>::max();
  int record_counter = 0;

  while (true) {
    const std::int64_t t_imu = static_cast<std::int64_t>(std::llround(imu_index * imu_period_us));
    const std::int64_t t_capture = mocap.next_frame_utime();
    const std::int64_t t_deliver = in_flight.empty() ? never : in_flight.front().publish_utime;
    const std::int64_t t_next = std::min(t_imu, std::min(t_capture, t_deliver));
    if (t_next > end_utime) break;
    if (t_capture == t_next) {
      const TruthSample& tr = truth.advance_to(t_capture);
      in_flight.push_back(mocap.capture(tr.mocap_input()));
    } else if (t_imu == t_next) {
      const TruthSample& tr = truth.advance_to(t_imu);
      const ImuSample sample = imu.sample(tr.imu_input());
      ekf.predict(sample);
      result.imu.push_back(sample);
      ++imu_index;
      if (++record_counter >= cfg.record_every) {
        record_counter = 0;
        SensingRecord rec;
        rec.utime = t_imu;
        rec.truth = true_state(tr, imu);
        rec.error = ekf.state() - rec.truth;
        rec.error[kPhi] = wrap_angle_rad(rec.error[kPhi]);
        rec.error[kTheta] = wrap_angle_rad(rec.error[kTheta]);
        rec.error[kPsi] = wrap_angle_rad(rec.error[kPsi]);
        rec.sigma = ekf.covariance().diagonal().cwiseSqrt();
        rec.nees = rec.error.dot(ekf.covariance().ldlt().solve(rec.error));
        result.records.push_back(rec);
      }
    } else {
      MocapPose pose = in_flight.front();
      in_flight.pop_front();
      if (cfg.pose_hook) cfg.pose_hook(pose);
      result.poses.push_back(pose);
      for (const PoseMeasurement& z : builder.push(pose)) ekf.add_measurement(z);
    }
  }
  result.counters = ekf.counters();
  result.frames = mocap.frame_count();
  result.frames_invalid = builder.frames_invalid();
  result.velocity_measurements = builder.velocity_measurements();
  result.attitude_only_measurements = builder.attitude_only_measurements();
  return result;
}

}  // namespace nimble
