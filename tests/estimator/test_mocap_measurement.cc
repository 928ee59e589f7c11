// Unit tests of the motion-capture measurement builder with its velocity differentiator
// (estimator/mocap_measurement.h), on clean frames and on frames of the emulator.

#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "core/attitude.h"
#include "estimator/mocap_measurement.h"
#include "sensors/mocap_emulator.h"

using namespace nimble;

namespace {

MocapConfig no_dropouts() {
  MocapConfig c;
  c.dropout_burst_rate_hz = 0.0;
  return c;
}

/// Frames of a noise-free body moving with constant NED velocity and constant yaw rate.
std::vector<MocapPose> clean_frames(int count, const Eigen::Vector3d& v_ned, double yaw_rate) {
  std::vector<MocapPose> frames;
  for (int n = 0; n < count; ++n) {
    MocapPose p;
    p.frame_number = n;
    p.utime = 250 + 5000 * static_cast<std::int64_t>(n);
    p.tracking_valid = true;
    p.position_ned_m = v_ned * (p.utime * 1e-6);
    p.q_body_to_ned = quaternion_from_euler_zyx(Eigen::Vector3d(0.3, 0.1, yaw_rate * p.utime * 1e-6));
    frames.push_back(p);
  }
  return frames;
}

}  // namespace

TEST_CASE("builder: attitude of every frame once, body velocity from a central difference", "[mocap_measurement]") {
  VelocityDifferentiatorConfig c;  // span 12, stride 5
  MocapMeasurementBuilder builder(c);
  const Eigen::Vector3d v_ned(0.8, -0.4, 0.2);
  const auto frames = clean_frames(200, v_ned, 0.0);
  std::vector<PoseMeasurement> out;
  for (const MocapPose& p : frames) {
    for (const PoseMeasurement& m : builder.push(p)) out.push_back(m);
  }
  for (const PoseMeasurement& m : builder.flush()) out.push_back(m);
  REQUIRE(out.size() == frames.size());
  std::vector<int> used(frames.size(), 0);
  int with_velocity = 0;
  for (const PoseMeasurement& m : out) {
    const auto n = static_cast<std::size_t>(m.frame_number);
    ++used[n];
    CHECK(m.utime == frames[n].utime);
    CHECK((m.euler_rad - euler_zyx_from_quaternion(frames[n].q_body_to_ned)).norm() < 1e-12);
    if (m.has_velocity) {
      ++with_velocity;
      CHECK((m.frame_number - c.span_frames / 2) % c.stride_frames == 0);
      const Eigen::Vector3d expected = frames[n].q_body_to_ned.toRotationMatrix().transpose() * v_ned;
      CHECK((m.velocity_body_mps - expected).norm() < 1e-9);
    }
  }
  for (int u : used) CHECK(u == 1);
  CHECK(with_velocity == 38);  // middles 6, 11, ..., 191 (end frame <= 199)
  CHECK(builder.velocity_measurements() == 38);
}

TEST_CASE("builder: differentiated velocity noise is white with sigma sqrt(2) sigma_p / span", "[mocap_measurement]") {
  MocapConfig mc = no_dropouts();
  mc.attitude_noise_sigma_rad.setZero();
  MocapEmulator mocap(mc, 10);
  VelocityDifferentiatorConfig c;
  MocapMeasurementBuilder builder(c);
  std::vector<Eigen::Vector3d> v;
  for (int n = 0; n < 100000; ++n) {
    MocapTruthInput t;
    t.utime = mocap.next_frame_utime();
    for (const PoseMeasurement& m : builder.push(mocap.capture(t))) {
      if (m.has_velocity) v.push_back(m.velocity_body_mps);
    }
  }
  const double expected = differentiated_velocity_sigma_mps(mc.position_sigma_m(), c.span_frames * 0.005);
  CHECK(expected == Approx(0.01256).epsilon(0.01));
  double var = 0.0, lag1 = 0.0, lag2 = 0.0;
  for (std::size_t i = 0; i < v.size(); ++i) {
    var += v[i].squaredNorm() / 3.0;
    if (i >= 1) lag1 += v[i].dot(v[i - 1]) / 3.0;
    if (i >= 2) lag2 += v[i].dot(v[i - 2]) / 3.0;
  }
  var /= v.size();
  lag1 /= (v.size() - 1);
  lag2 /= (v.size() - 2);
  INFO("sigma " << std::sqrt(var) << " m/s, lag-1 correlation " << lag1 / var << ", lag-2 " << lag2 / var);
  CHECK(std::sqrt(var) == Approx(expected).epsilon(0.03));
  // 20000 samples: standard error of a correlation 0.007.
  CHECK(std::fabs(lag1 / var) < 0.03);
  CHECK(std::fabs(lag2 / var) < 0.03);
}

TEST_CASE("builder: occluded or missing end frames give attitude only, gaps are counted", "[mocap_measurement]") {
  VelocityDifferentiatorConfig c;
  c.span_frames = 4;
  c.stride_frames = 3;  // pairs (0,4), (3,7), (6,10): middles 2, 5, 8
  MocapMeasurementBuilder builder(c);
  auto frames = clean_frames(12, Eigen::Vector3d(1, 0, 0), 0.0);
  frames[7].tracking_valid = false;  // end of the pair with middle 5
  std::vector<PoseMeasurement> out;
  for (const MocapPose& p : frames) {
    if (p.frame_number == 10) continue;  // never delivered: end of the pair with middle 8
    for (const PoseMeasurement& m : builder.push(p)) out.push_back(m);
  }
  for (const PoseMeasurement& m : builder.flush()) out.push_back(m);
  int velocity = 0;
  for (const PoseMeasurement& m : out) {
    if (m.has_velocity) {
      ++velocity;
      CHECK(m.frame_number == 2);
    }
  }
  CHECK(velocity == 1);
  CHECK(out.size() == 10);  // 12 frames - 1 occluded - 1 missing
  CHECK(builder.frames_missing() == 1);
  CHECK(builder.frames_invalid() == 1);
  // Out-of-order frames are dropped and counted.
  CHECK(builder.push(frames[3]).empty());
  CHECK(builder.frames_out_of_order() == 1);
}

TEST_CASE("differentiator config: even span, span not a multiple of the stride", "[mocap_measurement]") {
  VelocityDifferentiatorConfig odd;
  odd.span_frames = 5;
  CHECK_THROWS_WITH(MocapMeasurementBuilder(odd), Catch::Contains("span_frames"));
  VelocityDifferentiatorConfig shared;
  shared.span_frames = 12;
  shared.stride_frames = 4;
  CHECK_THROWS_WITH(MocapMeasurementBuilder(shared), Catch::Contains("not white"));
}
