// Functional tests of the message <-> core conversions (contract/messages.h): every field
// survives core -> message -> bytes -> message -> core exactly, and what a message does not
// carry comes back as its default.

#include <cmath>
#include <limits>
#include <random>
#include <string>
#include <type_traits>
#include <vector>

#include <catch2/catch.hpp>

#include "contract/messages.h"
#include "../support/lcm_samples.h"

using namespace nimble;

namespace {

template <typename T>
T through_bytes(const T& m) {
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
  T out{};
  REQUIRE(out.decode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
  return out;
}

std::mt19937_64 rng(20261125);
double draw() { return std::uniform_real_distribution<double>(-1e3, 1e3)(rng); }
Eigen::Vector3d draw3() { return Eigen::Vector3d(draw(), draw(), draw()); }

}  // namespace

TEST_CASE("messages: an IMU sample round-trips exactly", "[contract]") {
  for (int k = 0; k < 100; ++k) {
    ImuSample s;
    s.utime = static_cast<int64_t>(rng() >> 12);
    s.seq = k;
    s.gyro_radps = draw3();
    s.accel_mps2 = draw3();
    s.temperature_degc = draw();
    s.saturation_flags = static_cast<uint8_t>(rng() & 0x3f);
    const ImuSample back = contract::from_message(through_bytes(contract::to_message(s)));
    CHECK(back.utime == s.utime);
    CHECK(back.seq == s.seq);
    CHECK(back.gyro_radps == s.gyro_radps);
    CHECK(back.accel_mps2 == s.accel_mps2);
    CHECK(back.temperature_degc == s.temperature_degc);
    CHECK(back.saturation_flags == s.saturation_flags);
  }
}

TEST_CASE("messages: a motion-capture pose round-trips exactly, its publication time derived", "[contract]") {
  for (int k = 0; k < 100; ++k) {
    MocapPose p;
    p.utime = 1000000 + k * 5000;
    p.seq = k;
    p.frame_number = 7 + k;
    p.latency_us = 4000 + k;
    p.rigid_body_id = 3;
    p.position_ned_m = draw3();
    p.q_body_to_ned = Eigen::Quaterniond(Eigen::Vector4d::Random().normalized());
    p.tracking_valid = k % 7 != 0;
    p.mean_marker_error_m = 0.00085 * k;
    p.num_markers = static_cast<int16_t>(k % 12);
    p.publish_utime = p.utime + p.latency_us;
    const MocapPose back = contract::from_message(through_bytes(contract::to_message(p)));
    CHECK(back.utime == p.utime);
    CHECK(back.seq == p.seq);
    CHECK(back.frame_number == p.frame_number);
    CHECK(back.latency_us == p.latency_us);
    CHECK(back.rigid_body_id == p.rigid_body_id);
    CHECK(back.position_ned_m == p.position_ned_m);
    CHECK(back.q_body_to_ned.coeffs() == p.q_body_to_ned.coeffs());
    CHECK(back.tracking_valid == p.tracking_valid);
    CHECK(back.mean_marker_error_m == p.mean_marker_error_m);
    CHECK(back.num_markers == p.num_markers);
    CHECK(back.publish_utime == p.publish_utime);
  }
}

TEST_CASE("messages: the truth round-trips exactly, the side gust is not on the bus", "[contract]") {
  Truth t;
  t.time_s = 1.234567;
  t.position_ned_m = draw3();
  t.velocity_body_mps = draw3();
  t.euler_rad = draw3();
  t.quaternion_wxyz = Eigen::Vector4d(draw(), draw(), draw(), draw());
  t.omega_body_radps = draw3();
  t.specific_force_body_mps2 = draw3();
  t.angular_accel_body_radps2 = draw3();
  t.flap_freq_left_radps = draw();
  t.flap_freq_right_radps = draw();
  t.delta_f_radps = draw();
  t.throttle_pct = draw();
  t.dihedral_rad = draw();
  t.wing_root_rad = std::numeric_limits<double>::denorm_min();
  t.gust_v_mps = 0.5;
  const truth_state_t m = through_bytes(contract::to_message(t, 1234567, 42, 1234));
  CHECK(m.utime == 1234567);
  CHECK(m.seq == 42);
  CHECK(m.step == 1234);
  const Truth back = contract::from_message(m);
  CHECK(back.time_s == 1.234567);
  CHECK(back.position_ned_m == t.position_ned_m);
  CHECK(back.velocity_body_mps == t.velocity_body_mps);
  CHECK(back.euler_rad == t.euler_rad);
  CHECK(back.quaternion_wxyz == t.quaternion_wxyz);
  CHECK(back.omega_body_radps == t.omega_body_radps);
  CHECK(back.specific_force_body_mps2 == t.specific_force_body_mps2);
  CHECK(back.angular_accel_body_radps2 == t.angular_accel_body_radps2);
  CHECK(back.flap_freq_left_radps == t.flap_freq_left_radps);
  CHECK(back.flap_freq_right_radps == t.flap_freq_right_radps);
  CHECK(back.delta_f_radps == t.delta_f_radps);
  CHECK(back.throttle_pct == t.throttle_pct);
  CHECK(back.dihedral_rad == t.dihedral_rad);
  CHECK(back.wing_root_rad == t.wing_root_rad);
  CHECK(back.gust_v_mps == 0.0);
  // And message -> core -> message gives the same bytes.
  const truth_state_t again = contract::to_message(back, m.utime, m.seq, m.step);
  std::vector<uint8_t> a(static_cast<std::size_t>(m.getEncodedSize())), b(a.size());
  m.encode(a.data(), 0, static_cast<int>(a.size()));
  again.encode(b.data(), 0, static_cast<int>(b.size()));
  CHECK(a == b);
}

TEST_CASE("messages: an actuator command gives the plant every field it reads", "[contract]") {
  actuator_command_t m{};
  m.seq = 99;
  m.mode = actuator_command_t::MODE_DELTA_F;
  m.flap_freq_left_radps = 101.5;
  m.flap_freq_right_radps = 98.25;
  m.flap_freq_collective_radps = 99.875;
  m.delta_f_radps = 3.25;
  m.dihedral_rad = -0.125;
  m.wing_root_rad = 0.0625;
  const ActuatorCommand c = contract::from_message(through_bytes(m));
  CHECK(c.seq == 99);
  CHECK(c.mode == actuator_command_t::MODE_DELTA_F);
  CHECK(c.flap_freq_left_radps == 101.5);
  CHECK(c.flap_freq_right_radps == 98.25);
  CHECK(c.flap_freq_collective_radps == 99.875);
  CHECK(c.delta_f_radps == 3.25);
  CHECK(c.dihedral_rad == -0.125);
  CHECK(c.wing_root_rad == 0.0625);
}

namespace {

// True if message type M has a value (contract/messages.h declares its from_message).
template <typename M, typename = void>
struct has_value : std::false_type {};
template <typename M>
struct has_value<M, std::void_t<decltype(contract::from_message(std::declval<const M&>()))>> : std::true_type {};

// True if value type V converts to its message alone (the header is in the value).
template <typename V, typename = void>
struct header_in_value : std::false_type {};
template <typename V>
struct header_in_value<V, std::void_t<decltype(contract::to_message(std::declval<const V&>()))>> : std::true_type {};

// The message of the value of `m`: to_message(value), or to_message(value, utime, seq, step)
// where the header is not in the value (the truth).
template <typename M, typename V>
M message_again(const V& value, const M& m) {
  if constexpr (header_in_value<V>::value) {
    return contract::to_message(value);
  } else {
    return contract::to_message(value, m.utime, m.seq, m.step);
  }
}

}  // namespace

// Every message with a value (the generated list of types, contract/messages.h's pairs), each
// field distinct: message -> value -> message gives the same message, field by field. A field the
// conversion leaves out comes back as its default and is named.
TEST_CASE("messages: every stream message goes to its value and back with every field", "[contract]") {
  rig_test::Distinct g;
  std::vector<std::string> with_value;
  nimble::for_each_message_type([&](auto type) {
    using M = typename decltype(type)::type;
    if constexpr (has_value<M>::value) {
      INFO(M::getTypeName());
      with_value.push_back(M::getTypeName());
      M message{};
      rig_test::fill(message, g);
      rig_test::require_equal(message, message_again(contract::from_message(message), message));
    }
  });
  CHECK(with_value.size() >= 10);  // the values of core/rig_values.h today, each with its message
  // The pose's message time is its exposure (utime); the value adds when it is published.
  mocap_pose_t p{};
  rig_test::fill(p, g);
  CHECK(contract::from_message(p).publish_utime == p.utime + p.latency_us);
}
