// Unit tests: ActuatorInterface, the plant's end of the actuator link (decoding, clamps,
// command resolution, the command-timeout safe state), without transport.

#include <cmath>

#include <catch2/catch.hpp>

#include "plant/actuator_interface.h"

using namespace nimble::plant;

namespace {

constexpr int64_t kMs = 1000000;  // [ns]

const ActuatorInput kTrim{100.0, 100.0, 0.0, 0.0};

PlantConfig config_with(double flap_resolution_radps, double servo_resolution_rad) {
  PlantConfig c;
  c.command_timeout_s = 0.1;
  c.flap_command_resolution_radps = flap_resolution_radps;
  c.servo_command_resolution_rad = servo_resolution_rad;
  return c;
}

ActuatorCommand left_right(int64_t seq, double left, double right, double dihedral = 0.0, double wing_root = 0.0) {
  ActuatorCommand c;
  c.seq = seq;
  c.mode = static_cast<int8_t>(CommandMode::kLeftRight);
  c.flap_freq_left_radps = left;
  c.flap_freq_right_radps = right;
  c.dihedral_rad = dihedral;
  c.wing_root_rad = wing_root;
  return c;
}

}  // namespace

TEST_CASE("actuator interface: the trim until the first command, then the command as decoded from either mode",
          "[plant][actuators]") {
  ActuatorInterface a(config_with(0.0, 0.0), kTrim);
  CHECK(a.input().flap_freq_left_radps == 100.0);
  CHECK(a.last_command_seq() == -1);
  CHECK(a.command_age_us(5 * kMs) == -1);

  auto r = a.command(left_right(1, 90.0, 110.0, 0.2, -0.1), 2 * kMs);
  CHECK(r.accepted);
  CHECK(r.events.empty());
  CHECK(a.input().flap_freq_left_radps == 90.0);
  CHECK(a.input().flap_freq_right_radps == 110.0);
  CHECK(a.input().dihedral_rad == 0.2);
  CHECK(a.input().wing_root_rad == -0.1);
  CHECK(a.last_command_seq() == 1);
  CHECK(a.command_age_us(5 * kMs) == 3000);

  ActuatorCommand d;
  d.seq = 2;
  d.mode = static_cast<int8_t>(CommandMode::kDeltaF);
  d.flap_freq_collective_radps = 100.0;
  d.delta_f_radps = 20.0;
  d.flap_freq_left_radps = 1.0;  // ignored in this mode
  r = a.command(d, 3 * kMs);
  CHECK(r.accepted);
  CHECK(a.input().flap_freq_left_radps == 110.0);
  CHECK(a.input().flap_freq_right_radps == 90.0);
}

TEST_CASE("actuator interface: a command outside the actuator range is clamped, counted and reported",
          "[plant][actuators]") {
  ActuatorInterface a(config_with(0.0, 0.0), kTrim);
  const auto r = a.command(left_right(7, -5.0, 1000.0, 1.5, -2.0), 0);
  CHECK(r.accepted);
  REQUIRE(r.events.size() == 1);
  CHECK(r.events[0].kind == ActuatorEvent::Kind::kClamped);
  CHECK(r.events[0].message.find("seq 7") != std::string::npos);
  CHECK(a.input().flap_freq_left_radps == 0.0);
  CHECK(a.input().flap_freq_right_radps == ActuatorInterface::kMaxFlapRadps);
  CHECK(a.input().dihedral_rad == ActuatorInterface::kMaxServoRad);
  CHECK(a.input().wing_root_rad == -ActuatorInterface::kMaxServoRad);
  CHECK(a.counters().clamped == 1);
  CHECK(a.counters().rejected == 0);
}

TEST_CASE("actuator interface: commands are rounded to the command resolution, 0 leaves them as sent",
          "[plant][actuators]") {
  ActuatorInterface a(config_with(0.01, 1e-4), kTrim);
  a.command(left_right(1, 100.004, 100.006, 0.12344, -0.12346), 0);
  CHECK(a.input().flap_freq_left_radps == Approx(100.00).margin(1e-12));
  CHECK(a.input().flap_freq_right_radps == Approx(100.01).margin(1e-12));
  CHECK(a.input().dihedral_rad == Approx(0.1234).margin(1e-12));
  CHECK(a.input().wing_root_rad == Approx(-0.1235).margin(1e-12));
  // Exactly as the CAN decoder computes raw * factor: a value from the CAN link is kept.
  const double from_can = static_cast<double>(10123) * 0.01;
  a.command(left_right(2, from_can, from_can), 0);
  CHECK(a.input().flap_freq_left_radps == from_can);

  ActuatorInterface exact(config_with(0.0, 0.0), kTrim);
  exact.command(left_right(1, 100.004, 100.006, 0.12344), 0);
  CHECK(exact.input().flap_freq_left_radps == 100.004);
  CHECK(exact.input().dihedral_rad == 0.12344);
}

TEST_CASE("actuator interface: an unknown mode or a non-finite value is rejected, counted and leaves the input",
          "[plant][actuators]") {
  ActuatorInterface a(config_with(0.0, 0.0), kTrim);
  a.command(left_right(1, 90.0, 110.0), 0);

  ActuatorCommand bad_mode = left_right(2, 50.0, 50.0);
  bad_mode.mode = 5;
  auto r = a.command(bad_mode, 1 * kMs);
  CHECK_FALSE(r.accepted);
  REQUIRE(r.events.size() == 1);
  CHECK(r.events[0].kind == ActuatorEvent::Kind::kRejected);
  CHECK(r.events[0].message == "rejected actuator command seq 2: unknown mode 5");

  ActuatorCommand nan_delta;
  nan_delta.seq = 3;
  nan_delta.mode = static_cast<int8_t>(CommandMode::kDeltaF);
  nan_delta.flap_freq_collective_radps = 100.0;
  nan_delta.delta_f_radps = std::nan("");
  r = a.command(nan_delta, 2 * kMs);
  CHECK_FALSE(r.accepted);
  REQUIRE(r.events.size() == 1);
  CHECK(r.events[0].message == "rejected actuator command seq 3: flap_freq_left_radps is not finite");

  r = a.command(left_right(4, 90.0, 90.0, 0.0, INFINITY), 3 * kMs);
  CHECK_FALSE(r.accepted);
  CHECK(r.events[0].message.find("wing_root_rad is not finite") != std::string::npos);

  CHECK(a.counters().rejected == 3);
  CHECK(a.input().flap_freq_left_radps == 90.0);
  CHECK(a.input().flap_freq_right_radps == 110.0);
  CHECK(a.last_command_seq() == 1);
  CHECK(a.command_age_us(3 * kMs) == 3000);  // a rejected command does not count as one received
}

TEST_CASE("actuator interface: commands stopping for the timeout enter the safe state, the next valid one leaves it",
          "[plant][actuators]") {
  ActuatorInterface a(config_with(0.0, 0.0), kTrim);
  // No command since the start.
  CHECK_FALSE(a.update(100 * kMs));
  auto e = a.update(101 * kMs);
  REQUIRE(e);
  CHECK(e->kind == ActuatorEvent::Kind::kTimeout);
  CHECK(e->message.find("since the start") != std::string::npos);
  CHECK(a.safe_state());
  CHECK_FALSE(a.update(102 * kMs));  // reported once

  auto r = a.command(left_right(1, 80.0, 120.0, 0.3), 150 * kMs);
  CHECK(r.accepted);
  REQUIRE(r.events.size() == 1);
  CHECK(r.events[0].kind == ActuatorEvent::Kind::kResumed);
  CHECK_FALSE(a.safe_state());
  CHECK(a.input().flap_freq_left_radps == 80.0);

  // Commands stop again: the trim is applied, servos neutral, until a valid command.
  CHECK_FALSE(a.update(250 * kMs));
  e = a.update(251 * kMs);
  REQUIRE(e);
  CHECK(e->message.find("since the start") == std::string::npos);
  CHECK(a.input().flap_freq_left_radps == 100.0);
  CHECK(a.input().dihedral_rad == 0.0);
  ActuatorCommand bad = left_right(2, 80.0, 80.0);
  bad.mode = 9;
  a.command(bad, 260 * kMs);
  CHECK(a.safe_state());
  CHECK(a.command_age_us(260 * kMs) == 110000);
}
