// Unit tests of the motion-capture emulator (sensors/mocap_emulator.h).

#include <cmath>
#include <vector>

#include <catch2/catch.hpp>

#include "core/attitude.h"
#include "sensors/mocap_emulator.h"

using namespace nimble;

namespace {

MocapTruthInput still(std::int64_t utime) {
  MocapTruthInput t;
  t.utime = utime;
  t.position_ned_m = Eigen::Vector3d(1.0, -2.0, -1.5);
  t.q_body_to_ned = quaternion_from_euler_zyx(Eigen::Vector3d(0.2, -0.1, 1.0));
  return t;
}

MocapConfig no_dropouts() {
  MocapConfig c;
  c.dropout_burst_rate_hz = 0.0;
  return c;
}

}  // namespace

TEST_CASE("mocap position noise: mean 3-D error 0.85 mm (isotropic Gaussian, Maxwell norm)", "[mocap]") {
  const MocapConfig c = no_dropouts();
  CHECK(c.position_sigma_m() == Approx(0.85e-3 / (2.0 * std::sqrt(2.0 / M_PI))));
  CHECK(c.position_sigma_m() == Approx(0.5327e-3).epsilon(1e-3));
  MocapEmulator mocap(c, 3);
  const int n = 20000;
  double mean_norm = 0.0;
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const MocapTruthInput t = still(mocap.next_frame_utime());
    const MocapPose p = mocap.capture(t);
    REQUIRE(p.tracking_valid);
    const Eigen::Vector3d e = p.position_ned_m - t.position_ned_m;
    mean_norm += e.norm();
    var += e.cwiseAbs2();
    REQUIRE(p.mean_marker_error_m == Approx(e.norm()));
  }
  mean_norm /= n;
  var /= n;
  INFO("mean 3-D error " << mean_norm * 1e3 << " mm");
  CHECK(mean_norm == Approx(0.85e-3).epsilon(0.05));
  for (int i = 0; i < 3; ++i) CHECK(std::sqrt(var[i]) == Approx(c.position_sigma_m()).epsilon(0.05));
}

TEST_CASE("mocap attitude noise per body axis as configured", "[mocap]") {
  MocapConfig c = no_dropouts();
  c.attitude_noise_sigma_rad = Eigen::Vector3d(0.01, 0.005, 0.002);
  MocapEmulator mocap(c, 4);
  const int n = 20000;
  Eigen::Vector3d var = Eigen::Vector3d::Zero();
  for (int i = 0; i < n; ++i) {
    const MocapTruthInput t = still(mocap.next_frame_utime());
    const MocapPose p = mocap.capture(t);
    const Eigen::Vector3d delta = quaternion_log(t.q_body_to_ned.conjugate() * p.q_body_to_ned);
    var += delta.cwiseAbs2();
    REQUIRE(p.q_body_to_ned.w() >= 0.0);
  }
  var /= n;
  for (int i = 0; i < 3; ++i) CHECK(std::sqrt(var[i]) == Approx(c.attitude_noise_sigma_rad[i]).epsilon(0.05));
}

TEST_CASE("mocap frames: consecutive numbers, mid-exposure timestamps, latency", "[mocap]") {
  MocapConfig c = no_dropouts();
  c.first_frame_start_utime = 1000;
  c.exposure_us = 800;
  c.latency_us = 7000;
  MocapEmulator mocap(c, 5);
  CHECK(c.frame_period_us() == 5000);
  for (int n = 0; n < 1000; ++n) {
    const MocapPose p = mocap.capture(still(mocap.next_frame_utime()));
    REQUIRE(p.frame_number == n);
    REQUIRE(p.seq == n);
    REQUIRE(p.utime == 1000 + 5000 * n + 400);  // start + exposure / 2
    REQUIRE(p.latency_us == 7000);
    REQUIRE(p.publish_utime == p.utime + 7000);
    REQUIRE(p.num_markers == 4);
    REQUIRE(p.rigid_body_id == 1);
  }
}

TEST_CASE("mocap latency jitter is non-negative and keeps publication order", "[mocap]") {
  MocapConfig c = no_dropouts();
  c.latency_us = 2000;
  c.latency_jitter_sigma_us = 1500.0;
  MocapEmulator mocap(c, 6);
  std::int64_t last = 0;
  double mean = 0.0;
  const int n = 5000;
  for (int i = 0; i < n; ++i) {
    const MocapPose p = mocap.capture(still(mocap.next_frame_utime()));
    REQUIRE(p.latency_us >= 0);
    REQUIRE(p.publish_utime >= last);
    last = p.publish_utime;
    mean += p.latency_us;
  }
  CHECK(mean / n == Approx(2000.0).epsilon(0.1));
}

TEST_CASE("mocap occlusion bursts: dropout fraction and burst length as configured", "[mocap]") {
  MocapConfig c;
  c.dropout_burst_rate_hz = 1.0;
  c.dropout_mean_duration_s = 0.05;  // 10 frames
  MocapEmulator mocap(c, 7);
  const int n = 200000;  // 1000 s
  int invalid = 0, bursts = 0;
  bool previous_valid = true;
  for (int i = 0; i < n; ++i) {
    const MocapPose p = mocap.capture(still(mocap.next_frame_utime()));
    if (!p.tracking_valid) {
      ++invalid;
      if (previous_valid) ++bursts;
      REQUIRE(p.num_markers == 0);
      REQUIRE(p.position_ned_m.norm() == 0.0);
    }
    previous_valid = p.tracking_valid;
  }
  const double fraction = static_cast<double>(invalid) / n;
  const double mean_burst_s = static_cast<double>(invalid) / bursts * 0.005;
  INFO("dropout fraction " << fraction << " (expected " << c.expected_dropout_fraction() << "), bursts " << bursts
                           << ", mean length " << mean_burst_s << " s");
  // About 950 bursts: relative standard error of the fraction about 4.6 %; 15 % is 3.3 of them.
  CHECK(fraction == Approx(c.expected_dropout_fraction()).epsilon(0.15));
  CHECK(mean_burst_s == Approx(0.05).epsilon(0.15));
  CHECK(bursts / 1000.0 == Approx(1.0 * (1.0 - fraction)).epsilon(0.15));  // bursts start only while tracked
  CHECK(mocap.dropped_frame_count() == invalid);
}

TEST_CASE("mocap forced dropout window and noise independent of dropouts", "[mocap]") {
  MocapConfig c = no_dropouts();
  MocapEmulator a(c, 8), b(c, 8);
  b.add_forced_dropout(100000, 600000);  // 0.1 s .. 0.6 s
  for (int n = 0; n < 200; ++n) {
    const MocapTruthInput t = still(a.next_frame_utime());
    const MocapPose pa = a.capture(t), pb = b.capture(t);
    const bool inside = pb.utime >= 100000 && pb.utime < 600000;
    REQUIRE(pb.tracking_valid == !inside);
    if (!inside) REQUIRE((pa.position_ned_m - pb.position_ned_m).norm() == 0.0);
  }
  CHECK(b.dropped_frame_count() == 100);
}

TEST_CASE("mocap step(): interpolated truth at mid-exposure, released after the latency", "[mocap]") {
  MocapConfig c = no_dropouts();
  c.mean_position_error_m = 0.0;
  c.attitude_noise_sigma_rad.setZero();
  c.latency_us = 12000;
  MocapEmulator mocap(c, 9);
  const Eigen::Vector3d velocity(0.5, -0.25, 0.1);
  std::vector<MocapPose> got;
  for (std::int64_t t = 0; t <= 200000; t += 1000) {  // truth at 1 kHz
    MocapTruthInput truth;
    truth.utime = t;
    truth.position_ned_m = velocity * (t * 1e-6);
    truth.q_body_to_ned = quaternion_exp(Eigen::Vector3d(0, 0, 2.0 * t * 1e-6));  // 2 rad/s yaw
    for (const MocapPose& p : mocap.step(truth)) {
      REQUIRE(p.publish_utime <= t);
      REQUIRE(p.publish_utime > t - 1000);  // released at the first truth sample after publication
      got.push_back(p);
    }
  }
  REQUIRE(got.size() >= 35);
  for (std::size_t i = 0; i < got.size(); ++i) {
    const MocapPose& p = got[i];
    REQUIRE(p.frame_number == static_cast<std::int64_t>(i));
    CHECK((p.position_ned_m - velocity * (p.utime * 1e-6)).norm() < 1e-12);
    CHECK(euler_zyx_from_quaternion(p.q_body_to_ned)[2] == Approx(2.0 * p.utime * 1e-6).margin(1e-9));
  }
}

TEST_CASE("mocap config validation names the field", "[mocap]") {
  MocapConfig c;
  c.frame_rate_hz = 300.0;  // 3333.3 us
  CHECK_THROWS_WITH(MocapEmulator(c, 1), Catch::Contains("frame_rate_hz"));
  MocapConfig d;
  d.exposure_us = 6000;
  CHECK_THROWS_WITH(MocapEmulator(d, 1), Catch::Contains("exposure_us"));
}

TEST_CASE("mocap: a truth far ahead of the frame schedule skips to it instead of capturing every frame", "[mocap]") {
  // Found by fuzz_node_mocap: a TRUTH 10^11 us after the previous one made step() capture 2 * 10^7
  // frames (a process that hangs). Up to 1000 frames are caught up; further ahead, the schedule
  // moves to the truth and the frames between count as dropped.
  MocapConfig c = no_dropouts();
  c.latency_us = 0;
  MocapEmulator mocap(c, 7);
  CHECK(mocap.step(still(0)).empty());                 // the first frame is half an exposure later
  CHECK(mocap.step(still(5000 * 999)).size() >= 998);  // within reach: every frame
  const std::int64_t far = 100000000000;               // 10^11 us
  const std::vector<MocapPose> poses = mocap.step(still(far));
  CHECK(poses.size() <= 2);
  CHECK(mocap.dropped_frame_count() > 19000000);
  CHECK(mocap.next_frame_utime() > far);
  CHECK(mocap.next_frame_utime() <= far + c.frame_period_us());
}
