#include "estimator_test_support.h"

#include <cmath>

#include "core/attitude.h"
#include "estimator/mocap_measurement.h"

namespace nimble::test {

RecordedData record_data(const TruthProfile& profile, const SensingConfig& s, double duration_s) {
  RecordedData d;
  TruthTrajectory truth(profile, 0);
  ImuModel imu(s.imu, s.seed);
  MocapEmulator mocap(s.mocap, s.seed + 1000003ULL);
  const std::int64_t end = static_cast<std::int64_t>(std::llround(duration_s * 1e6));
  std::int64_t k = 0;
  while (true) {
    const std::int64_t t_imu = static_cast<std::int64_t>(std::llround(k * 1e6 / s.imu.sample_rate_hz));
    const std::int64_t t_cap = mocap.next_frame_utime();
    if (std::min(t_imu, t_cap) > end) break;
    if (t_cap < t_imu) {
      d.frames.push_back(mocap.capture(truth.advance_to(t_cap).mocap_input()));
    } else {
      const TruthSample& tr = truth.advance_to(t_imu);
      d.imu.push_back(imu.sample(tr.imu_input()));
      EkfState x;
      x << tr.euler_rad, tr.velocity_body_mps, imu.gyro_bias_radps(), imu.accel_bias_mps2();
      d.truth_at_imu.push_back(x);
      ++k;
    }
  }
  return d;
}

EkfState estimation_error(const EkfState& estimate, const EkfState& truth) {
  EkfState e = estimate - truth;
  for (int i = 0; i < 3; ++i) e[i] = wrap_angle_rad(e[i]);
  return e;
}

void feed(AttitudeVelocityEkf& ekf, const RecordedData& data, std::int64_t delay_us,
          const VelocityDifferentiatorConfig& differentiator, const std::function<void(MocapPose&)>& frame_hook,
          const std::function<void(std::size_t)>& after_imu) {
  MocapMeasurementBuilder builder(differentiator);
  EkfState x0 = data.truth_at_imu.front();
  x0.tail<6>().setZero();
  ekf.initialize(data.imu.front().utime, x0, ekf.config().initial_covariance());
  std::size_t next_frame = 0;
  for (std::size_t k = 0; k < data.imu.size(); ++k) {
    ekf.predict(data.imu[k]);
    if (after_imu) after_imu(k);
    const std::int64_t until = k + 1 < data.imu.size() ? data.imu[k + 1].utime : data.imu[k].utime + 1;
    while (next_frame < data.frames.size() && data.frames[next_frame].utime + delay_us < until) {
      MocapPose pose = data.frames[next_frame++];
      if (frame_hook) frame_hook(pose);
      for (const PoseMeasurement& z : builder.push(pose)) ekf.add_measurement(z);
    }
  }
}

EkfConfig exact_replay(EkfConfig c) {
  c.replay_relinearise_attitude_rad = 0.0;
  c.replay_relinearise_velocity_mps = 0.0;
  c.replay_relinearise_gyro_bias_radps = 0.0;
  return c;
}

EkfConfig reusing_replay(EkfConfig c) {
  c.replay_relinearise_attitude_rad = 0.02;
  c.replay_relinearise_velocity_mps = 0.05;
  c.replay_relinearise_gyro_bias_radps = 0.05;
  return c;
}

}  // namespace nimble::test
