// Functional test: the launcher's run monitor judges stream messages by their decoded fields;
// a motion-capture pose is due latency_us after its mid-exposure stamp; what it cannot trust
// (bytes that do not decode, a decoder that throws, a seq that does not continue its publisher's,
// a publisher that is not in the run) is counted as malformed and left out of every figure. The
// roll tracking error is the controller's reference against the true roll.
#include <cmath>
#include <cstdint>
#include <random>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"
#include "launcher/run_monitor.h"
#include "tests/support/encoded.h"

using nimble::controller_status_t;
using nimble::heartbeat_t;
using nimble::mocap_pose_t;
using nimble::truth_state_t;
using nimble::contract::channels::kControllerStatus;
using nimble::contract::channels::kHeartbeat;
using nimble::contract::channels::kMocapPose;
using nimble::contract::channels::kTruth;
using nimble::launcher::MonitorConfig;
using nimble::launcher::RunMonitor;

namespace {

constexpr int64_t kT0Ns = 1000000000;  // CLOCK_MONOTONIC of simulated time 0

using nimble::test::encoded;

RunMonitor real_time_monitor() {
  MonitorConfig cfg;
  cfg.lockstep = false;
  cfg.t0_monotonic_ns = kT0Ns;
  cfg.late_threshold_us = 2000;
  return RunMonitor(cfg);
}

mocap_pose_t pose(int64_t seq, int64_t utime, int32_t latency_us) {
  mocap_pose_t p{};  // only the times matter here
  p.utime = utime;
  p.seq = seq;
  p.latency_us = latency_us;
  return p;
}

/// Receive time [ns] of a message that arrives `after_us` after simulated time `sim_us`.
int64_t received_at(int64_t sim_us, int64_t after_us) { return kT0Ns + (sim_us + after_us) * 1000; }

}  // namespace

TEST_CASE("a pose is late only counting from its stamp plus its latency", "[launcher][monitor]") {
  RunMonitor mon = real_time_monitor();
  // Stamped at 10 ms, published 5 ms later, received 1 ms after that: on time.
  auto on_time = encoded(pose(0, 10000, 5000));
  mon.on_message(kMocapPose, on_time.data(), static_cast<int>(on_time.size()), received_at(10000, 6000));
  CHECK(mon.channels(1.0, 1.0).at(kMocapPose).late == 0);
  // The same arrival with no latency declared is 6 ms after it was due: late.
  auto no_latency = encoded(pose(1, 15000, 0));
  mon.on_message(kMocapPose, no_latency.data(), static_cast<int>(no_latency.size()), received_at(15000, 6000));
  CHECK(mon.channels(1.0, 1.0).at(kMocapPose).late == 1);
  // A latency that does not explain the delay leaves the pose late.
  auto still_late = encoded(pose(2, 20000, 1000));
  mon.on_message(kMocapPose, still_late.data(), static_cast<int>(still_late.size()), received_at(20000, 4000));
  const auto c = mon.channels(1.0, 1.0).at(kMocapPose);
  CHECK(c.late == 2);
  CHECK(c.count == 3);
  CHECK(c.drops == 0);
  CHECK(c.malformed == 0);
}

TEST_CASE("a pose that does not decode is malformed, not judged", "[launcher][monitor]") {
  RunMonitor mon = real_time_monitor();
  auto buf = encoded(pose(0, 10000, 5000));
  buf.resize(buf.size() - 1);  // truncated: the header is intact, the pose is not
  mon.on_message(kMocapPose, buf.data(), static_cast<int>(buf.size()), received_at(10000, 60000));
  const auto c = mon.channels(1.0, 1.0).at(kMocapPose);
  CHECK(c.count == 0);  // the count is of messages the monitor could read
  CHECK(c.malformed == 1);
  CHECK(c.late == 0);
}

TEST_CASE("other stream messages are due at their utime", "[launcher][monitor]") {
  RunMonitor mon = real_time_monitor();
  truth_state_t t{};
  t.utime = 10000;
  t.seq = 0;
  auto on_time = encoded(t);
  mon.on_message(kTruth, on_time.data(), static_cast<int>(on_time.size()), received_at(10000, 1500));
  t.utime = 11000;
  t.seq = 2;  // one lost
  auto late = encoded(t);
  mon.on_message(kTruth, late.data(), static_cast<int>(late.size()), received_at(11000, 2500));
  const auto c = mon.channels(1.0, 1.0).at(kTruth);
  CHECK(c.count == 2);
  CHECK(c.late == 1);
  CHECK(c.drops == 1);
}

TEST_CASE("garbage on the rig's channels is malformed and stays out of the flight figures", "[launcher][monitor]") {
  MonitorConfig cfg;
  cfg.lockstep = true;
  cfg.processes = {"plant", "controller"};
  RunMonitor mon(cfg);
  // The real flight: 100 TRUTH messages, |phi| <= 0.1 rad.
  truth_state_t t{};
  t.quaternion_wxyz[0] = 1.0;
  for (int k = 0; k < 100; ++k) {
    t.utime = 1000 * k;
    t.seq = k;
    t.euler_rad[0] = 0.1 * std::sin(0.1 * k);
    const auto b = encoded(t);
    mon.on_message(kTruth, b.data(), static_cast<int>(b.size()), 0);
  }
  std::mt19937_64 rng(7);
  int garbage = 0;
  // TRUTH that decodes (the right fingerprint, random fields, random seq): a stray publisher.
  for (int k = 0; k < 200; ++k, ++garbage) {
    truth_state_t g = t;
    g.seq = static_cast<int64_t>(rng());
    g.euler_rad[0] = 1e4 * static_cast<double>(static_cast<int64_t>(rng() % 2000) - 1000);
    const auto b = encoded(g);
    mon.on_message(kTruth, b.data(), static_cast<int>(b.size()), 0);
  }
  // Random bytes, half of them behind TRUTH's real fingerprint.
  const auto real = encoded(t);
  for (int k = 0; k < 200; ++k, ++garbage) {
    std::vector<uint8_t> b(static_cast<std::size_t>(rng() % 600));
    for (auto& x : b) x = static_cast<uint8_t>(rng());
    if (k % 2 == 0 && b.size() >= 8) std::copy(real.begin(), real.begin() + 8, b.begin());
    mon.on_message(kTruth, b.data(), static_cast<int>(b.size()), 0);
  }
  const auto c = mon.channels(0.1, 0.1).at(kTruth);
  CHECK(c.count == 100);
  CHECK(c.malformed == garbage);
  CHECK(c.drops == 0);
  CHECK(mon.flight().samples == 100);
  CHECK(mon.flight().max_abs_phi <= 0.1);
  CHECK(mon.flight().finite);
}

TEST_CASE("a decoder that throws, and a publisher not in the run, are malformed", "[launcher][monitor]") {
  MonitorConfig cfg;
  cfg.processes = {"plant"};
  RunMonitor mon(cfg);
  heartbeat_t hb{};
  hb.process = "plant";
  hb.state = heartbeat_t::STATE_READY;
  auto b = encoded(hb);
  mon.on_message(kHeartbeat, b.data(), static_cast<int>(b.size()), 0);
  CHECK(mon.heartbeat_state("plant") == heartbeat_t::STATE_READY);
  // A string whose encoded length is 0 (LCM 1.3.1's decoder threw; the rig's build refuses it,
  // cmake/LcmDecodeChecks.cmake): bytes 24-27 hold the length of `process` (after fingerprint,
  // utime and seq).
  auto zero_length = b;
  zero_length[24] = zero_length[25] = zero_length[26] = zero_length[27] = 0;
  CHECK_NOTHROW(mon.on_message(kHeartbeat, zero_length.data(), static_cast<int>(zero_length.size()), 0));
  // A heartbeat from a process the run does not have.
  heartbeat_t stray = hb;
  stray.process = "intruder";
  stray.seq = 1;
  auto s = encoded(stray);
  mon.on_message(kHeartbeat, s.data(), static_cast<int>(s.size()), 0);
  CHECK(mon.heartbeat_state("intruder") == -1);
  const auto c = mon.channels(1.0, 1.0).at(kHeartbeat);
  CHECK(c.count == 1);
  CHECK(c.malformed == 2);
}

TEST_CASE("roll tracking: the controller's reference against the newest TRUTH at or before its cycle",
          "[launcher][monitor]") {
  MonitorConfig cfg;
  cfg.lockstep = true;
  RunMonitor mon(cfg);
  CHECK(mon.tracking().samples == 0);  // no controller, nothing to judge
  constexpr double kDeg = M_PI / 180.0;
  truth_state_t t{};
  t.quaternion_wxyz[0] = 1.0;
  controller_status_t st{};
  st.gain_set = "fast";
  // TRUTH every 1 ms with phi = 10 deg up to 5 ms, then 20 deg; a control cycle every 2 ms
  // (utime 0, 2, 4, 6 ms, one of them between two truths) with the reference at 15 deg. Its own
  // roll error is against the roll it measured (an estimate 3 deg off): not what is judged.
  int64_t status_seq = 0;
  for (int k = 0; k <= 8; ++k) {
    t.utime = 1000 * k;
    t.seq = k;
    t.euler_rad[0] = (k <= 5 ? 10.0 : 20.0) * kDeg;
    const auto tb = encoded(t);
    mon.on_message(kTruth, tb.data(), static_cast<int>(tb.size()), 0);
    if (k % 2 == 0 || k == 5) {
      st.utime = k == 5 ? 5500 : 1000 * k;  // 5.5 ms: the newest truth before it is 5 ms's
      st.seq = status_seq++;
      st.roll_ref_rad = 15.0 * kDeg;
      st.roll_error_rad = st.roll_ref_rad - (t.euler_rad[0] + 3.0 * kDeg);
      const auto sb = encoded(st);
      mon.on_message(kControllerStatus, sb.data(), static_cast<int>(sb.size()), 0);
    }
  }
  const auto tr = mon.tracking();
  // Cycles at 0, 2, 4, 5.5 ms: +5 deg; at 6 and 8 ms: -5 deg.
  REQUIRE(tr.samples == 6);
  CHECK(tr.rms_deg == Approx(5.0));
  CHECK(tr.max_deg == Approx(5.0));
  REQUIRE(tr.half_cycles.size() == 2);
  CHECK(tr.half_cycles[0].peak_deg == Approx(5.0));
  CHECK(tr.half_cycles[1].peak_deg == Approx(-5.0));
  CHECK(tr.half_cycles[1].start_s == Approx(0.0055 + 0.0005 * 0.5));  // the interpolated zero crossing
  CHECK(tr.half_cycles[0].reference_range_deg == Approx(0.0));
}

TEST_CASE("the flight's trace takes the first TRUTH at or after each grid time", "[launcher][monitor]") {
  MonitorConfig cfg;
  cfg.lockstep = true;
  cfg.trace_interval_us = 20000;  // 50 Hz
  RunMonitor mon(cfg);
  truth_state_t t{};
  t.quaternion_wxyz[0] = 1.0;
  // TRUTH at 1 kHz from 0 to 99 ms, then a gap to 150 ms.
  std::vector<int64_t> stamps;
  for (int k = 0; k < 100; ++k) stamps.push_back(1000 * k);
  stamps.push_back(150000);
  int64_t seq = 0;
  for (const int64_t utime : stamps) {
    t.utime = utime;
    t.seq = seq++;
    t.omega_body_radps[0] = 1e-6 * static_cast<double>(utime);  // p tells the stamp it came from
    t.velocity_body_mps[1] = -t.omega_body_radps[0];
    t.euler_rad[0] = 2.0 * t.omega_body_radps[0];
    const auto b = encoded(t);
    mon.on_message(kTruth, b.data(), static_cast<int>(b.size()), 0);
  }
  const nimble::launcher::FlightSummary& f = mon.flight();
  CHECK(f.trace_dt_s == Approx(0.02));
  // Grid times 0, 20, 40, 60, 80 ms from their own TRUTH; 100, 120, 140 ms from the one at 150.
  REQUIRE(f.trace_p.size() == 8);
  CHECK(f.trace_p[0] == 0.0);
  CHECK(f.trace_p[3] == Approx(0.06));
  CHECK(f.trace_p[4] == Approx(0.08));
  CHECK(f.trace_p[5] == Approx(0.15));
  CHECK(f.trace_p[7] == Approx(0.15));
  CHECK(f.trace_v[3] == Approx(-0.06));
  CHECK(f.trace_phi[3] == Approx(0.12));
  // No grid, no trace.
  RunMonitor plain{MonitorConfig{}};
  const auto b = encoded(t);
  plain.on_message(kTruth, b.data(), static_cast<int>(b.size()), 0);
  CHECK(plain.flight().trace_p.empty());
  CHECK(plain.flight().trace_dt_s == 0.0);
}
