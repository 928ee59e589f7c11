// Functional tests: the plant, controller, estimator and motion-capture processes' node classes on
// the in-process memq:// provider, the test playing the other side of the lockstep protocol.

#include <chrono>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/attitude_setpoint_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/run_control_t.hpp>
#include <nimble/step_ack_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"
#include "controller/controller_node.h"
#include "estimator/estimator_node.h"
#include "mocap/mocap_node.h"
#include "plant/plant_node.h"

using namespace nimble;
using namespace nimble::contract::channels;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

run_control_t start_lockstep(double duration_s, const std::vector<std::string>& participants) {
  run_control_t m;
  m.utime = 0;
  m.seq = 0;
  m.command = run_control_t::COMMAND_START;
  m.clock_mode = run_control_t::CLOCK_MODE_LOCKSTEP;
  m.t0_monotonic_ns = 0;
  m.duration_ns = static_cast<int64_t>(duration_s * 1e9);
  m.run_id = "test";
  m.participants = participants;
  m.num_participants = static_cast<int32_t>(participants.size());
  return m;
}

run_control_t stop_command() {
  run_control_t m = start_lockstep(0, {});
  m.seq = 1;
  m.command = run_control_t::COMMAND_STOP;
  return m;
}

/// What the plant node publishes, collected from `bus`; its FINISHED heartbeat stops the run.
struct PlantOutputs {
  explicit PlantOutputs(transport::Bus& bus) {
    bus.subscribe<truth_state_t>(kTruth, [this](const truth_state_t& m) { truth.push_back(m); });
    bus.subscribe<actuator_feedback_t>(kActuatorFeedback,
                                       [this](const actuator_feedback_t& m) { feedback.push_back(m); });
    bus.subscribe<fault_event_t>(kFault, [this](const fault_event_t& m) { faults.push_back(m); });
    bus.subscribe<heartbeat_t>(kHeartbeat, [&bus](const heartbeat_t& m) {
      if (m.state == heartbeat_t::STATE_FINISHED) bus.publish(kRunControl, stop_command());
    });
  }
  PlantOutputs(const PlantOutputs&) = delete;
  PlantOutputs& operator=(const PlantOutputs&) = delete;

  std::vector<truth_state_t> truth;
  std::vector<actuator_feedback_t> feedback;
  std::vector<fault_event_t> faults;
};

/// Plays the lockstep master for `participant` on `bus` and starts the run: once the participant
/// runs, advance(0), then advance(next_due_ns) on each of its STEP_ACKs (publish the inputs up to
/// that time and the tick), until it is due no more within `duration_s`; then stops the run.
void play_lockstep_master(transport::Bus& bus, const std::string& participant, double duration_s,
                          const std::function<void(int64_t)>& advance) {
  bus.subscribe<step_ack_t>(kStepAck, [&bus, duration_s, advance](const step_ack_t& ack) {
    if (ack.next_due_ns >= static_cast<int64_t>(duration_s * 1e9)) {
      bus.publish(kRunControl, stop_command());
      return;
    }
    advance(ack.next_due_ns);
  });
  bus.subscribe<heartbeat_t>(kHeartbeat, [advance, started = false](const heartbeat_t& m) mutable {
    if (m.state == heartbeat_t::STATE_RUNNING && !started) {
      started = true;
      advance(0);
    }
  });
  bus.publish(kRunControl, start_lockstep(duration_s, {participant}));
}

}  // namespace

TEST_CASE("plant node: steps in lockstep on a participant's acks, applies commands, reports faults",
          "[plant][process]") {
  const Scenario scenario = load_scenario(kConfigs + "hover.yaml");
  plant::PlantNode plant(scenario, {"plant", "", "memq://"});
  transport::Bus& bus = plant.node().bus();

  PlantOutputs out(bus);
  std::vector<truth_state_t>& truth = out.truth;
  std::vector<actuator_feedback_t>& feedback = out.feedback;
  std::vector<fault_event_t>& faults = out.faults;
  int ticks = 0;
  // The test is the participant "controller": it answers every tick with a command
  // (delta_f = +20 rad/s) and an acknowledgement, and sends bad commands at step 10 and 11.
  bus.subscribe<rig_clock_t>(kRigClock, [&](const rig_clock_t& tick) {
    ++ticks;
    actuator_command_t cmd{};
    cmd.utime = tick.utime;
    cmd.seq = tick.step;
    cmd.mode = actuator_command_t::MODE_DELTA_F;
    cmd.flap_freq_collective_radps = 102.497;
    cmd.delta_f_radps = 20.0;
    cmd.source = "test";
    if (tick.step == 10) cmd.delta_f_radps = std::nan("");
    bus.publish(kActuatorCommand, cmd);
    if (tick.step == 11) {
      const char garbage[] = "not an actuator command";
      bus.lcm().publish(kActuatorCommand, garbage, sizeof garbage);
    }
    step_ack_t ack{};
    ack.utime = tick.utime;
    ack.seq = tick.step;
    ack.step = tick.step;
    ack.next_due_ns = tick.sim_time_ns + tick.dt_ns;
    ack.process = "controller";
    bus.publish(kStepAck, ack);
  });
  bus.publish(kRunControl, start_lockstep(0.2, {"controller"}));

  REQUIRE(plant.run() == transport::kExitOk);
  CHECK(ticks == 201);
  REQUIRE(truth.size() == 201);
  CHECK(feedback.size() == 21);
  for (std::size_t i = 0; i < truth.size(); ++i) {
    REQUIRE(truth[i].seq == static_cast<int64_t>(i));
    REQUIRE(truth[i].utime == static_cast<int64_t>(i) * 1000);
    REQUIRE(truth[i].step == static_cast<int64_t>(i));
  }
  // Positive delta_f rolls right wing down: p > 0 and phi > 0 after 0.2 s.
  CHECK(truth.back().delta_f_radps > 5.0);
  CHECK(truth.back().omega_body_radps[0] > 0.0);
  CHECK(truth.back().euler_rad[0] > 0.0);
  // The bad commands were reported, named, and did not stop the plant.
  bool nan_reported = false, garbage_reported = false;
  for (const auto& f : faults) {
    if (f.code == fault_event_t::CODE_MESSAGE_MALFORMED && f.message.find("not finite") != std::string::npos) {
      nan_reported = true;
    }
    if (f.code == fault_event_t::CODE_MESSAGE_MALFORMED && f.channel == kActuatorCommand &&
        f.message.find("cannot decode") != std::string::npos) {
      garbage_reported = true;
    }
  }
  CHECK(nan_reported);
  CHECK(garbage_reported);
  CHECK(bus.stats().at(kActuatorCommand).malformed == 1);
}

TEST_CASE("plant node: commands stop, safe state held and reported", "[plant][process]") {
  const Scenario scenario = load_scenario(kConfigs + "hover.yaml");
  plant::PlantNode plant(scenario, {"plant", "", "memq://"});
  transport::Bus& bus = plant.node().bus();
  PlantOutputs out(bus);
  std::vector<truth_state_t>& truth = out.truth;
  std::vector<actuator_feedback_t>& feedback = out.feedback;
  std::vector<fault_event_t>& faults = out.faults;
  // Commands with delta_f = 30 rad/s for the first 50 ms only; acknowledgements always.
  bus.subscribe<rig_clock_t>(kRigClock, [&](const rig_clock_t& tick) {
    if (tick.sim_time_ns < 50000000) {
      actuator_command_t cmd{};
      cmd.utime = tick.utime;
      cmd.seq = tick.step;
      cmd.mode = actuator_command_t::MODE_LEFT_RIGHT;
      cmd.flap_freq_left_radps = 102.497 + 15;
      cmd.flap_freq_right_radps = 102.497 - 15;
      bus.publish(kActuatorCommand, cmd);
    }
    step_ack_t ack{};
    ack.step = tick.step;
    ack.next_due_ns = tick.sim_time_ns + tick.dt_ns;
    ack.process = "controller";
    bus.publish(kStepAck, ack);
  });
  bus.publish(kRunControl, start_lockstep(0.5, {"controller"}));
  REQUIRE(plant.run() == transport::kExitOk);

  // Timeout 0.1 s after the last command (t = 0.049 s): safe state from about t = 0.15 s.
  int timeouts = 0;
  for (const auto& f : faults) {
    if (f.code == fault_event_t::CODE_COMMAND_TIMEOUT) {
      ++timeouts;
      CHECK(f.rig_utime == Approx(150000).margin(2000));
    }
  }
  CHECK(timeouts == 1);
  REQUIRE_FALSE(feedback.empty());
  CHECK_FALSE(feedback[10].safe_state);  // t = 0.1 s
  CHECK(feedback.back().safe_state);
  CHECK(feedback.back().cmd_seq == 49);
  // In the safe state delta_f decays back to zero (trim frequencies on both wings).
  CHECK(std::fabs(truth.back().delta_f_radps) < 0.05 * 30 * 8.97 / 12.56);
}

TEST_CASE("controller node: acknowledges when due, flies the manoeuvre's set-points, restores roll",
          "[controller][process]") {
  // The test is the plant and feeds TRUTH: ideal sensing.
  const Scenario scenario = load_scenario(kConfigs + "id_doublet_train_fast.yaml", {{"run.controller_input", "truth"}});
  ControllerNode controller(scenario, {"controller", "", "memq://"});
  transport::Bus& bus = controller.node().bus();
  std::vector<actuator_command_t> commands;
  std::vector<attitude_setpoint_t> setpoints;
  std::vector<controller_status_t> status;
  std::vector<int64_t> acked_steps;
  bus.subscribe<actuator_command_t>(kActuatorCommand, [&](const actuator_command_t& m) { commands.push_back(m); });
  bus.subscribe<attitude_setpoint_t>(kAttitudeSetpoint, [&](const attitude_setpoint_t& m) { setpoints.push_back(m); });
  bus.subscribe<controller_status_t>(kControllerStatus, [&](const controller_status_t& m) { status.push_back(m); });

  // The test is the plant: a vehicle frozen at phi = +0.1 rad, ticking at 1 kHz up to
  // the controller's next due time.
  const int64_t dt_ns = 1000000;
  const double duration_s = 1.5;
  int64_t step = 0;
  const auto tick = [&](int64_t k) {
    truth_state_t t{};
    t.utime = k * dt_ns / 1000;
    t.seq = k;
    t.step = k;
    t.euler_rad[0] = 0.1;
    t.quaternion_wxyz[0] = 1.0;
    bus.publish(kTruth, t);
    rig_clock_t c{};
    c.utime = t.utime;
    c.seq = k;
    c.step = k;
    c.sim_time_ns = k * dt_ns;
    c.dt_ns = dt_ns;
    bus.publish(kRigClock, c);
  };
  bus.subscribe<step_ack_t>(kStepAck, [&](const step_ack_t& ack) {
    acked_steps.push_back(ack.step);
    if (ack.next_due_ns > static_cast<int64_t>(duration_s * 1e9)) {
      bus.publish(kRunControl, stop_command());
      return;
    }
    step = (ack.next_due_ns + dt_ns - 1) / dt_ns;  // first plant step at or after the due time
    tick(step);
  });
  // The first tick goes out once the controller runs (it listens for the clock from then on).
  bus.subscribe<heartbeat_t>(kHeartbeat, [&](const heartbeat_t& m) {
    if (m.state == heartbeat_t::STATE_RUNNING && step == 0) tick(0);
  });
  bus.publish(kRunControl, start_lockstep(duration_s, {"controller"}));
  REQUIRE(controller.run() == transport::kExitOk);

  // 512 Hz over 1.5 s: cycles at n / 512 s for n = 0..767.
  CHECK(commands.size() == 768);
  CHECK(setpoints.size() == 768);
  CHECK(status.size() == 768);
  CHECK(acked_steps.size() == 768);
  for (std::size_t n = 0; n < commands.size(); ++n) {
    REQUIRE(commands[n].seq == static_cast<int64_t>(n));
    REQUIRE(commands[n].utime == static_cast<int64_t>(n) * 1953125 / 1000);
  }
  // During the first hover second the set-point is level and the roll error restoring:
  // phi = +0.1 rad (right wing down) needs negative delta_f (left slower than right).
  const auto& c = commands[400];
  CHECK(setpoints[400].roll_sp_rad == 0.0);
  CHECK(c.delta_f_radps < 0.0);
  CHECK(c.flap_freq_left_radps < c.flap_freq_right_radps);
  CHECK(status[400].roll_error_rad < 0.0);
  CHECK(status[400].gain_set == "fast");
  // After 1 s the doublet starts: negative half first (thesis Fig 7.7).
  bool doublet_seen = false;
  for (const auto& sp : setpoints) {
    if (sp.segment_name == "doublet_7hz") {
      doublet_seen = true;
      CHECK(sp.utime >= 1000000);
      CHECK(sp.roll_sp_rad < 0.0);
      break;
    }
  }
  CHECK(doublet_seen);
}

TEST_CASE(
    "estimator node: ESTIMATE carries the EKF's counters, when the motion capture falls behind by more "
    "than the history, its poses are dropped, counted and raised as a FAULT naming the key",
    "[estimator][process]") {
  const Scenario scenario = load_scenario(kConfigs + "hover.yaml");
  EstimatorNode estimator(scenario, {"estimator", "", "memq://"});
  transport::Bus& bus = estimator.node().bus();
  std::vector<estimator_state_t> estimates;
  std::vector<fault_event_t> faults;
  bus.subscribe<estimator_state_t>(kEstimate, [&](const estimator_state_t& m) { estimates.push_back(m); });
  bus.subscribe<fault_event_t>(kFault, [&](const fault_event_t& m) { faults.push_back(m); });

  // The test is the plant and the motion capture: a vehicle at rest, IMU at 512 Hz, poses at
  // 200 Hz with 5 ms latency; from frame 100 (0.5 s) on the motion capture lags 200 ms.
  const double duration_s = 1.0;
  int64_t imu_k = 0, frame = 0, clock_seq = 0;
  const auto pose_times = [](int64_t f) {  // (utime, latency) of frame f
    return std::make_pair<int64_t, int32_t>(f * 5000, f < 100 ? 5000 : 200000);
  };
  const auto publish_until = [&](int64_t t_ns) {  // inputs published up to t_ns, then the clock
    const int64_t t_us = t_ns / 1000;
    for (; imu_k * 1000000 / 512 <= t_us; ++imu_k) {
      imu_sample_t s{};
      s.utime = imu_k * 1000000 / 512;
      s.seq = imu_k;
      // A real IMU at rest: gravity and a little noise (a sample that repeats bit for bit for
      // 50 samples is a stuck sensor to the estimator).
      s.accel_mps2[2] = -9.81 + 1e-4 * static_cast<double>((imu_k * 7919) % 11 - 5);
      s.temperature_degc = 25.0;
      bus.publish(kImu, s);
    }
    for (;; ++frame) {
      const auto [utime, latency] = pose_times(frame);
      if (utime + latency > t_us) break;
      mocap_pose_t p{};
      p.utime = utime;
      p.seq = frame;
      p.frame_number = frame;
      p.latency_us = latency;
      p.rigid_body_id = 1;
      p.position_m[2] = -1.5;
      p.quaternion_wxyz[0] = 1.0;
      p.tracking_valid = true;
      p.num_markers = 4;
      bus.publish(kMocapPose, p);
    }
    rig_clock_t c{};
    c.utime = t_us;
    c.seq = clock_seq;
    c.step = clock_seq++;
    c.sim_time_ns = t_ns;
    c.dt_ns = 1953125;
    bus.publish(kRigClock, c);
  };
  play_lockstep_master(bus, "estimator", duration_s, publish_until);
  REQUIRE(estimator.run() == transport::kExitOk);

  REQUIRE(estimates.size() > 400);
  const estimator_state_t& last = estimates.back();
  // Measurements from the middle frames 94 on (emitted once their end frame, 100 or later,
  // arrives 200 ms late) up to the last frame delivered before 1 s.
  CHECK(last.poses_too_old >= 55);  // 60 measured
  CHECK(last.poses_too_new == 0);
  CHECK(last.velocity_windows_uncovered == 0);
  CHECK(last.imu_rejected == 0);
  CHECK(last.imu_gaps == 0);
  CHECK(last.poses_accepted > 90);
  CHECK(std::fabs(last.velocity_body_mps[1]) < 0.01);  // still at rest
  int dropped = 0;
  for (const auto& f : faults) {
    if (f.message.find("dropped by the EKF") == std::string::npos) continue;
    ++dropped;
    INFO(f.message);
    CHECK(f.severity == fault_event_t::SEVERITY_WARNING);
    CHECK(f.code == fault_event_t::CODE_MEASUREMENT_OUT_OF_WINDOW);
    CHECK(f.channel == kMocapPose);
    CHECK(f.message.find("older than the rollback history of 100.0 ms") != std::string::npos);
    CHECK(f.message.find("sensing.ekf.latency.history_s") != std::string::npos);
  }
  CHECK(dropped == 1);  // at most one a second of rig time
}

TEST_CASE(
    "lockstep participant: a tick that overtakes RUN_CONTROL start is handled once the run starts, a repeated "
    "tick is acknowledged again without running twice",
    "[controller][process][lockstep]") {
  // RUN_CONTROL start (from the launcher) and the master's first RIG_CLOCK come from different
  // senders; the tick may arrive first. The master repeats a tick whose acknowledgement is
  // missing; the participant must answer without running its tasks again.
  const Scenario scenario = load_scenario(kConfigs + "id_doublet_train_fast.yaml", {{"run.controller_input", "truth"}});
  ControllerNode controller(scenario, {"controller", "", "memq://"});
  transport::Bus& bus = controller.node().bus();
  std::vector<actuator_command_t> commands;
  std::vector<int64_t> acked_steps;
  bus.subscribe<actuator_command_t>(kActuatorCommand, [&](const actuator_command_t& m) { commands.push_back(m); });
  truth_state_t t{};
  t.quaternion_wxyz[0] = 1.0;
  rig_clock_t c{};
  c.dt_ns = 1000000;
  c.run_id = "test";
  bus.subscribe<step_ack_t>(kStepAck, [&](const step_ack_t& ack) {
    acked_steps.push_back(ack.step);
    if (acked_steps.size() == 1) {
      bus.publish(kRigClock, c);  // the same tick again, as the master sends it
    } else {
      bus.publish(kRunControl, stop_command());
    }
  });
  // When the participant says READY it listens for the clock but has not seen the start:
  // the tick goes out first, then the start.
  bool started = false;
  bus.subscribe<heartbeat_t>(kHeartbeat, [&](const heartbeat_t& m) {
    if (m.state != heartbeat_t::STATE_READY || started) return;
    started = true;
    bus.publish(kTruth, t);
    bus.publish(kRigClock, c);
    bus.publish(kRunControl, start_lockstep(1.0, {"controller"}));
  });
  REQUIRE(controller.run() == transport::kExitOk);
  CHECK(acked_steps == std::vector<int64_t>{0, 0});
  CHECK(commands.size() == 1);
}

namespace {

/// A pose the motion-capture node published and the tick [us] it went out at.
struct ReceivedPose {
  mocap_pose_t pose;
  int64_t tick_utime;
};

/// Runs the motion-capture node of `scenario` in lockstep for `duration_s`, the test being the
/// plant: TRUTH at 1 kHz of a vehicle moving north at 0.5 m/s, 1.5 m up, level; a tick at the
/// first plant step at or after each time the node is due. Returns the poses it published.
std::vector<ReceivedPose> run_mocap(const Scenario& scenario, double duration_s) {
  MocapNode mocap(scenario, {"mocap", "", "memq://"});
  transport::Bus& bus = mocap.node().bus();
  std::vector<ReceivedPose> poses;
  const int64_t dt_ns = 1000000;
  int64_t published = -1;  // last plant step whose TRUTH went out
  int64_t tick_utime = -1;
  const auto tick = [&](int64_t k) {
    for (++published; published <= k; ++published) {
      truth_state_t t{};
      t.utime = published * dt_ns / 1000;
      t.seq = published;
      t.step = published;
      t.position_ned_m[0] = 0.5 * static_cast<double>(t.utime) / 1e6;
      t.position_ned_m[2] = -1.5;
      t.quaternion_wxyz[0] = 1.0;
      bus.publish(kTruth, t);
    }
    published = k;
    rig_clock_t c{};
    c.utime = k * dt_ns / 1000;
    c.seq = k;
    c.step = k;
    c.sim_time_ns = k * dt_ns;
    c.dt_ns = dt_ns;
    c.run_id = "test";
    tick_utime = c.utime;
    bus.publish(kRigClock, c);
  };
  bus.subscribe<mocap_pose_t>(kMocapPose, [&](const mocap_pose_t& m) { poses.push_back({m, tick_utime}); });
  // At the first plant step at or after each due time.
  play_lockstep_master(bus, "mocap", duration_s, [&](int64_t t_ns) { tick((t_ns + dt_ns - 1) / dt_ns); });
  REQUIRE(mocap.run() == transport::kExitOk);
  return poses;
}

}  // namespace

TEST_CASE(
    "mocap node: 200 Hz poses from the plant-rate truth, each out and stamped at the tick after its "
    "latency, seeded marker noise",
    "[mocap][process]") {
  const Scenario scenario = load_scenario(kConfigs + "hover.yaml");
  const std::vector<ReceivedPose> poses = run_mocap(scenario, 1.0);

  // Frames every 5 ms at mid-exposure (500 us exposure from t = 0), out 5 ms later: those out
  // before the last tick at 995 ms.
  REQUIRE(poses.size() == 198);
  double error_sum = 0;
  int valid = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const mocap_pose_t& p = poses[i].pose;
    INFO("frame " << p.frame_number);
    REQUIRE(p.frame_number == static_cast<int64_t>(i));
    REQUIRE(p.utime == static_cast<int64_t>(i) * 5000 + 250);
    // Released at the first frame tick at or after its due time (the configured 5 ms after
    // mid-exposure), and stamped with that tick: its latency runs to the tick it went out at.
    CHECK(poses[i].tick_utime >= p.utime + 5000);
    CHECK(poses[i].tick_utime < p.utime + 5000 + 5000);
    CHECK(p.utime + p.latency_us == poses[i].tick_utime);
    if (!p.tracking_valid) continue;
    const double north_m = 0.5 * static_cast<double>(p.utime) / 1e6;
    error_sum += std::sqrt(std::pow(p.position_m[0] - north_m, 2) + std::pow(p.position_m[1], 2) +
                           std::pow(p.position_m[2] + 1.5, 2));
    ++valid;
  }
  REQUIRE(valid > 150);
  const double rate_hz = 1e6 * static_cast<double>(poses.size() - 1) /
                         static_cast<double>(poses.back().pose.utime - poses.front().pose.utime);
  CHECK(rate_hz == Approx(200.0));
  // Marker noise: a mean 3-D error of 0.85 mm (about 170 frames: within 15 %).
  const double mean_error_mm = 1000.0 * error_sum / valid;
  INFO("mean 3-D position error " << mean_error_mm << " mm over " << valid << " frames");
  CHECK(mean_error_mm == Approx(0.85).epsilon(0.15));

  // Seeded: the same seed gives the same poses, another seed other noise.
  const std::vector<ReceivedPose> again = run_mocap(scenario, 1.0);
  const std::vector<ReceivedPose> other = run_mocap(load_scenario(kConfigs + "hover.yaml", {{"seed", "2"}}), 1.0);
  REQUIRE(again.size() == poses.size());
  REQUIRE_FALSE(other.empty());
  bool same = true;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    for (int k = 0; k < 3; ++k) same = same && again[i].pose.position_m[k] == poses[i].pose.position_m[k];
    same = same && again[i].pose.tracking_valid == poses[i].pose.tracking_valid;
  }
  CHECK(same);
  CHECK(other[0].pose.position_m[0] != poses[0].pose.position_m[0]);
}

TEST_CASE("controller node: a message time at the end of int64 is taken without overflow", "[controller][process]") {
  // Found by fuzz_node_controller: the input's time [us] was multiplied by 1000 for the
  // input-triggered task, and a TRUTH (or ESTIMATE) stamped near INT64_MAX overflowed (undefined
  // behaviour; the sanitizer build fails this test without transport::message_us_to_ns).
  for (const char* input : {"truth", "estimate"}) {
    INFO("run.controller_input=" << input);
    const Scenario scenario = load_scenario(kConfigs + "hover.yaml", {{"run.controller_input", input}});
    ControllerNode controller(scenario, {"controller", "", "memq://"});
    transport::Bus& bus = controller.node().bus();
    if (std::string(input) == "truth") {
      truth_state_t t{};
      t.utime = std::numeric_limits<int64_t>::max();
      t.quaternion_wxyz[0] = 1.0;
      bus.publish(kTruth, t);
    } else {
      estimator_state_t e{};
      e.utime = std::numeric_limits<int64_t>::max();
      e.imu_utime = std::numeric_limits<int64_t>::max();
      bus.publish(kEstimate, e);
    }
    bus.drain();
    const std::string channel = std::string(input) == "truth" ? kTruth : kEstimate;
    CHECK(bus.stats().at(channel).received == 1);
    CHECK(bus.stats().at(channel).malformed == 0);
  }
  CHECK(transport::message_us_to_ns(std::numeric_limits<int64_t>::max()) == transport::kMaxMessageTimeNs);
  CHECK(transport::message_us_to_ns(std::numeric_limits<int64_t>::min()) == -transport::kMaxMessageTimeNs);
  CHECK(transport::message_us_to_ns(-1234) == -1234000);
}

TEST_CASE("estimator and mocap nodes: an input time outside any run is refused with a FAULT",
          "[estimator][mocap][process]") {
  // Found by fuzz_node_estimator and fuzz_node_mocap: an IMU sample or TRUTH stamped days ahead
  // made the EKF integrate step by step, and the emulator capture every frame, up to it.
  const Scenario scenario = load_scenario(kConfigs + "hover.yaml");
  EstimatorNode estimator(scenario, {"estimator", "", "memq://"});
  MocapNode mocap(scenario, {"mocap", "", "memq://"});
  for (transport::Bus* bus : {&estimator.node().bus(), &mocap.node().bus()}) {
    std::vector<fault_event_t> faults;
    bus->subscribe<fault_event_t>(kFault, [&](const fault_event_t& f) { faults.push_back(f); });
    const bool is_estimator = bus == &estimator.node().bus();
    if (is_estimator) {
      imu_sample_t imu{};
      imu.utime = transport::kMaxSimUtime + 1;
      bus->publish(kImu, imu);
    } else {
      truth_state_t t{};
      t.utime = -5;
      t.quaternion_wxyz[0] = 1.0;
      bus->publish(kTruth, t);
    }
    bus->drain();
    bus->drain();  // the FAULT the handler published
    INFO((is_estimator ? "estimator" : "mocap"));
    REQUIRE(faults.size() == 1);
    CHECK(faults[0].code == fault_event_t::CODE_MESSAGE_MALFORMED);
    CHECK(faults[0].channel == (is_estimator ? kImu : kTruth));
    CHECK(faults[0].message.find("outside any run") != std::string::npos);
  }
  CHECK(transport::plausible_sim_utime(0));
  CHECK(transport::plausible_sim_utime(transport::kMaxSimUtime));
  CHECK_FALSE(transport::plausible_sim_utime(-1));
}

TEST_CASE("a process whose run never starts gives up after run.start_wait_s, named, with a FAULT",
          "[controller][process]") {
  // A node started by hand for a run that is refused (or whose launcher died) is told by nobody;
  // it must end by itself instead of waiting for ever.
  const Scenario scenario = load_scenario(kConfigs + "hover.yaml", {{"run.start_wait_s", "0.3"}});
  ControllerNode controller(scenario, {"controller", "", "memq://"});
  transport::Bus& bus = controller.node().bus();
  std::vector<fault_event_t> faults;
  bus.subscribe<fault_event_t>(kFault, [&](const fault_event_t& f) { faults.push_back(f); });
  const auto t0 = std::chrono::steady_clock::now();
  const int code = controller.run();
  const double waited_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  bus.drain();
  CHECK(code == transport::kExitFault);
  CHECK(waited_s >= 0.3);
  CHECK(waited_s < 5.0);
  REQUIRE_FALSE(faults.empty());
  CHECK(faults.back().code == fault_event_t::CODE_COMMAND_TIMEOUT);
  CHECK(std::string(faults.back().message).find("no run started within 0.3 s (run.start_wait_s)") != std::string::npos);
}
