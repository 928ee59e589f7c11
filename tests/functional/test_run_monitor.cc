// Functional test: the launcher's run monitor judges stream messages by their decoded fields;
// a motion-capture pose is due latency_us after its mid-exposure stamp.
#include <cstdint>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"
#include "launcher/run_monitor.h"

using nimble::mocap_pose_t;
using nimble::truth_state_t;
using nimble::contract::channels::kMocapPose;
using nimble::contract::channels::kTruth;
using nimble::launcher::MonitorConfig;
using nimble::launcher::RunMonitor;

namespace {

constexpr int64_t kT0Ns = 1000000000;  // CLOCK_MONOTONIC of simulated time 0

template <typename T>
std::vector<uint8_t> encode(const T& m) {
  std::vector<uint8_t> buf(static_cast<std::size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
  return buf;
}

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
  auto on_time = encode(pose(0, 10000, 5000));
  mon.on_message(kMocapPose, on_time.data(), static_cast<int>(on_time.size()), received_at(10000, 6000));
  CHECK(mon.channels(1.0, 1.0).at(kMocapPose).late == 0);
  // The same arrival with no latency declared is 6 ms after it was due: late.
  auto no_latency = encode(pose(1, 15000, 0));
  mon.on_message(kMocapPose, no_latency.data(), static_cast<int>(no_latency.size()), received_at(15000, 6000));
  CHECK(mon.channels(1.0, 1.0).at(kMocapPose).late == 1);
  // A latency that does not explain the delay leaves the pose late.
  auto still_late = encode(pose(2, 20000, 1000));
  mon.on_message(kMocapPose, still_late.data(), static_cast<int>(still_late.size()), received_at(20000, 4000));
  const auto c = mon.channels(1.0, 1.0).at(kMocapPose);
  CHECK(c.late == 2);
  CHECK(c.count == 3);
  CHECK(c.drops == 0);
  CHECK(c.malformed == 0);
}

TEST_CASE("a pose that does not decode is malformed, not judged", "[launcher][monitor]") {
  RunMonitor mon = real_time_monitor();
  auto buf = encode(pose(0, 10000, 5000));
  buf.resize(buf.size() - 1);  // truncated: the header is intact, the pose is not
  mon.on_message(kMocapPose, buf.data(), static_cast<int>(buf.size()), received_at(10000, 60000));
  const auto c = mon.channels(1.0, 1.0).at(kMocapPose);
  CHECK(c.count == 1);
  CHECK(c.malformed == 1);
  CHECK(c.late == 0);
}

TEST_CASE("other stream messages are due at their utime", "[launcher][monitor]") {
  RunMonitor mon = real_time_monitor();
  truth_state_t t{};
  t.utime = 10000;
  t.seq = 0;
  auto on_time = encode(t);
  mon.on_message(kTruth, on_time.data(), static_cast<int>(on_time.size()), received_at(10000, 1500));
  t.utime = 11000;
  t.seq = 2;  // one lost
  auto late = encode(t);
  mon.on_message(kTruth, late.data(), static_cast<int>(late.size()), received_at(11000, 2500));
  const auto c = mon.channels(1.0, 1.0).at(kTruth);
  CHECK(c.count == 2);
  CHECK(c.late == 1);
  CHECK(c.drops == 1);
}
