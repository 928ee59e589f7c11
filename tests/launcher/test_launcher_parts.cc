// Unit tests of the launcher's parts that know nothing of processes: the verdict, the report
// writers, the message pipe to the recording thread, the recorder's timestamps, the in-process
// CAN bus and the sweep's arithmetic.

#include <linux/can.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <sstream>
#include <stdexcept>
#include <thread>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <yaml-cpp/yaml.h>

#include <nimble/rig_clock_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "can_bridge/inprocess_can_bus.h"
#include "contract/channels.h"
#include "launcher/message_pipe.h"
#include "launcher/recorder.h"
#include "launcher/run_report.h"
#include "transport/clock.h"
#include "campaign/sweep.h"
#include "launcher/verdict.h"
#include "tests/support/scratch.h"
#include "tests/support/encoded.h"

using namespace nimble::launcher;
using namespace nimble::campaign;

namespace {

FlightSummary calm_flight() {
  FlightSummary f;
  f.samples = 100;
  f.max_abs_phi = 20.0 * M_PI / 180.0;
  f.final_phi = 1.0 * M_PI / 180.0;
  f.final_p = 0.1;
  f.final_v = 0.05;
  return f;
}

}  // namespace

TEST_CASE("verdict: controlled and back at hover is ok", "[launcher]") {
  const Verdict v = judge_run(calm_flight(), JudgeConfig{}, false, "");
  CHECK(v.exit_code == kRunOk);
  CHECK(v.text == "ok");
  CHECK(v.controlled);
  CHECK(v.hover);
}

TEST_CASE("verdict: roll beyond the limit, non-finite truth or no truth is not controlled", "[launcher]") {
  FlightSummary f = calm_flight();
  f.max_abs_phi = 81.0 * M_PI / 180.0;
  Verdict v = judge_run(f, JudgeConfig{}, false, "");
  CHECK(v.exit_code == kRunNotControlled);
  CHECK_FALSE(v.controlled);
  CHECK_FALSE(v.hover);
  CHECK(v.text == "completed, vehicle NOT controlled");
  JudgeConfig wide;
  wide.max_phi_deg = 90.0;
  CHECK(judge_run(f, wide, false, "").exit_code == kRunOk);  // the limit is the judge's

  f = calm_flight();
  f.finite = false;
  CHECK(judge_run(f, JudgeConfig{}, false, "").exit_code == kRunNotControlled);
  f = calm_flight();
  f.max_abs_theta = 61.0 * M_PI / 180.0;
  CHECK(judge_run(f, JudgeConfig{}, false, "").exit_code == kRunNotControlled);
  CHECK(judge_run(FlightSummary{}, JudgeConfig{}, false, "").exit_code == kRunNotControlled);
}

TEST_CASE("verdict: controlled but not back at hover is still ok", "[launcher]") {
  FlightSummary f = calm_flight();
  f.final_v = 0.31;
  const Verdict v = judge_run(f, JudgeConfig{}, false, "");
  CHECK(v.exit_code == kRunOk);
  CHECK(v.controlled);
  CHECK_FALSE(v.hover);
}

TEST_CASE("verdict: a failure outranks the flight, an interruption outranks both", "[launcher]") {
  const Verdict failed = judge_run(calm_flight(), JudgeConfig{}, false, "process 'plant' died\n  details");
  CHECK(failed.exit_code == kRunFailed);
  CHECK(failed.text == "failed: process 'plant' died");  // the first line only
  const Verdict stopped = judge_run(calm_flight(), JudgeConfig{}, true, "process 'plant' died");
  CHECK(stopped.exit_code == kRunInterrupted);
  CHECK(stopped.text == "interrupted");
}

TEST_CASE("report: the text and the JSON carry the same run", "[launcher]") {
  RunReport r;
  r.scenario = "unit";
  r.clock = kClockInprocess;
  r.seed = 42;
  r.transport = "in process";
  r.log_file = "x.lcmlog";
  r.sim_time_s = 6.0;
  r.wall_time_s = 0.03;
  r.channels[nimble::contract::channels::kTruth] = ChannelSummary{6001, 1000.2, 1000.0, 0, 0, 0, false};
  r.flight = calm_flight();
  r.faults.push_back(FaultRecord{"plant", 2, 13, nimble::contract::channels::kActuatorCommand, "clamped", 1.5});
  r.faults.push_back(FaultRecord{"plant", 2, 13, nimble::contract::channels::kActuatorCommand, "clamped again", 1.6});
  r.processes.push_back(ProcessOutcome{"plant", 1, true, 0, 0, "in process, returned 0", 0, ""});
  r.verdict = judge_run(r.flight, JudgeConfig{}, false, "");
  std::ostringstream text;
  write_report_text(text, r);
  CHECK(text.str().find("== run summary: unit ==") != std::string::npos);
  CHECK(text.str().find("inprocess, seed 42") != std::string::npos);
  CHECK(text.str().find("200.00x real time") != std::string::npos);
  CHECK(text.str().find("[plant COMMAND_CLAMPED t=1.500 s] clamped") != std::string::npos);
  CHECK(text.str().find("(2 in all)") != std::string::npos);  // one line per process and code
  CHECK(text.str().find("clamped again") == std::string::npos);
  CHECK(text.str().find("result     ok") != std::string::npos);
  const YAML::Node j = YAML::Load(report_json(r));
  CHECK(j["scenario"].as<std::string>() == "unit");
  CHECK(j["clock"].as<std::string>() == "inprocess");
  CHECK(j["seed"].as<int>() == 42);
  CHECK(j["speed_x_realtime"].as<double>() == Approx(200.0));
  CHECK(j["channels"][nimble::contract::channels::kTruth]["count"].as<int>() == 6001);
  CHECK(j["faults"][0]["code"].as<int>() == 13);
  CHECK(j["processes"]["plant"]["exit_code"].as<int>() == 0);
  CHECK(j["exit_code"].as<int>() == kRunOk);
  CHECK(j["result"].as<std::string>() == "ok");
}

TEST_CASE("message pipe: every message arrives on the other thread, in order, with its bytes", "[launcher]") {
  const std::string a = "A", b = "BB";
  std::vector<std::string> got;
  std::thread::id sink_thread;
  {
    MessagePipe pipe(
        [&](const std::string& channel, const void* data, int size, int64_t stamp, bool /*own*/) {
          sink_thread = std::this_thread::get_id();
          got.push_back(channel + ":" + std::string(static_cast<const char*>(data), size) + ":" +
                        std::to_string(stamp));
        },
        64, 2);  // small batches and two in flight: the sender waits, nothing is dropped
    for (int i = 0; i < 5000; ++i) {
      const std::string payload = std::to_string(i);
      pipe.send(i % 3 == 0 ? &a : &b, payload.data(), static_cast<int>(payload.size()), i);
    }
    pipe.close();
    pipe.close();  // idempotent
  }
  REQUIRE(got.size() == 5000);
  for (int i = 0; i < 5000; ++i) {
    const std::string want = (i % 3 == 0 ? a : b) + ":" + std::to_string(i) + ":" + std::to_string(i);
    if (got[i] != want) FAIL("message " << i << " is '" << got[i] << "', expected '" << want << "'");
  }
  CHECK(sink_thread != std::this_thread::get_id());
}

TEST_CASE("message pipe: an exception in the sink reaches close()", "[launcher]") {
  const std::string c = "C";
  MessagePipe pipe([](const std::string&, const void*, int, int64_t, bool) { throw std::runtime_error("disk full"); });
  pipe.send(&c, "x", 1, 0);
  CHECK_THROWS_WITH(pipe.close(), "disk full");
}

TEST_CASE("in-process CAN bus: frames reach every other endpoint, FD only where FD is on", "[launcher][can]") {
  using nimble::can::FramePort;
  using nimble::can::InprocessCanBus;
  using nimble::can::ReceivedFrame;
  using nimble::can::ReceiveResult;
  using nimble::can::SendResult;
  InprocessCanBus bus;
  auto flight = bus.attach("vcan0", true);
  auto rig = bus.attach("vcan0", true);
  auto classical = bus.attach("vcan0", false);
  CHECK(flight->fd() == -1);

  can_frame f{};
  f.can_id = 0x110;
  f.len = 8;
  for (int i = 0; i < 8; ++i) f.data[i] = static_cast<uint8_t>(i);
  CHECK(flight->send(f) == SendResult::kSent);
  ReceivedFrame rx;
  CHECK(flight->receive(&rx, 0) == ReceiveResult::kTimeout);  // not its own frame
  REQUIRE(rig->receive(&rx, 0) == ReceiveResult::kFrame);
  CHECK_FALSE(rx.is_fd);
  CHECK(rx.frame.can_id == 0x110);
  CHECK(std::memcmp(rx.frame.data, f.data, 8) == 0);
  CHECK(rx.has_kernel_time);
  REQUIRE(classical->receive(&rx, 0) == ReceiveResult::kFrame);

  canfd_frame fd{};
  fd.can_id = 0x120;
  fd.len = 8;
  fd.flags = CANFD_BRS;
  fd.data[7] = 0xAB;
  CHECK(flight->send(fd) == SendResult::kSent);
  REQUIRE(rig->receive(&rx, 0) == ReceiveResult::kFrame);
  CHECK(rx.is_fd);
  CHECK(rx.fd_flags == CANFD_BRS);
  CHECK(rx.frame.can_id == 0x120);  // the first 8 bytes as a classical view
  CHECK(rx.frame.data[7] == 0xAB);
  CHECK(classical->receive(&rx, 0) == ReceiveResult::kTimeout);  // a classical socket never sees FD
  CHECK(classical->send(fd) == SendResult::kError);              // nor may it send one
  CHECK(classical->stats().last_errno == EINVAL);

  CHECK(flight->stats().frames_sent == 2);
  CHECK(flight->stats().fd_frames_sent == 1);
  CHECK(rig->stats().frames_received == 2);
  CHECK(rig->stats().fd_frames_received == 1);
  CHECK(bus.frames() == 2);
}

// --- rig sweep's parts ------------------------------------------------------------------

TEST_CASE("sweep: --vary splits values at top-level commas only", "[launcher][sweep]") {
  const Vary v = parse_vary("model=a.yaml, b.yaml");
  CHECK(v.key == "model");
  CHECK(v.values == std::vector<std::string>{"a.yaml", "b.yaml"});
  const Vary p = parse_vary("processes=[plant,controller],[plant,controller,mocap,estimator]");
  CHECK(p.values == std::vector<std::string>{"[plant,controller]", "[plant,controller,mocap,estimator]"});
  CHECK_THROWS_WITH(parse_vary("model"), Catch::Contains("key=value1,value2"));
  CHECK_THROWS_WITH(parse_vary("=1,2"), Catch::Contains("key=value1,value2"));
  CHECK_THROWS_WITH(parse_vary("a=1,,2"), Catch::Contains("empty value"));
  CHECK_THROWS_WITH(parse_vary("a=[1,2"), Catch::Contains("unbalanced"));
}

TEST_CASE("sweep: seed ranges", "[launcher][sweep]") {
  CHECK(parse_seed_range("1-20") == std::pair<uint64_t, uint64_t>{1, 20});
  CHECK(parse_seed_range("7") == std::pair<uint64_t, uint64_t>{7, 7});
  for (const char* bad : {"20-1", "a-b", "1-", "-3", "1.5", "", "1-2-3", "99999999999999999999999"}) {
    INFO(bad);
    CHECK_THROWS_WITH(parse_seed_range(bad), Catch::Contains("--seeds"));
  }
}

TEST_CASE("sweep: parameter sets are every combination, the first --vary slowest", "[launcher][sweep]") {
  const auto sets = parameter_sets({parse_vary("a=1,2"), parse_vary("b=x,y,z")});
  REQUIRE(sets.size() == 6);
  CHECK(sets[0].label == "a=1 b=x");
  CHECK(sets[2].label == "a=1 b=z");
  CHECK(sets[3].label == "a=2 b=x");
  REQUIRE(sets[5].overrides.size() == 2);
  CHECK(sets[5].overrides[0].key_path == "a");
  CHECK(sets[5].overrides[1].value == "z");
  const auto one = parameter_sets({});
  REQUIRE(one.size() == 1);
  CHECK(one[0].overrides.empty());
  CHECK(one[0].label == "scenario as given");
}

TEST_CASE("sweep: percentiles interpolate between order statistics", "[launcher][sweep]") {
  const std::vector<double> v = {5, 1, 4, 2, 3};
  CHECK(percentile(v, 0) == 1);
  CHECK(percentile(v, 50) == 3);
  CHECK(percentile(v, 100) == 5);
  CHECK(percentile(v, 25) == 2);
  CHECK(percentile(v, 90) == Approx(4.6));  // numpy.percentile([1..5], 90)
  CHECK(percentile({7.0}, 95) == 7.0);
  CHECK(std::isnan(percentile({}, 50)));
}

TEST_CASE("sweep: the summary, the JSON runs list and the CSV agree", "[launcher][sweep]") {
  SweepResult r;
  r.scenario = "unit";
  r.clock = kClockInprocess;
  r.sets = parameter_sets({parse_vary("model=a,b")});
  for (std::size_t s = 0; s < 2; ++s) {
    for (uint64_t seed = 1; seed <= 3; ++seed) {
      SweepRun run;
      run.set = s;
      run.seed = seed;
      run.controlled = !(s == 1 && seed == 2);
      run.exit_code = run.controlled ? kRunOk : kRunNotControlled;
      run.verdict = run.controlled ? "ok" : "completed, vehicle NOT controlled";
      run.figures["max_abs_phi_deg"] = 10.0 * static_cast<double>(s + 1) + static_cast<double>(seed);
      r.runs.push_back(run);
    }
  }
  std::ostringstream text;
  write_sweep_text(text, r);
  CHECK(text.str().find("6 runs: 2 parameter sets x 3 seeds (1-3)") != std::string::npos);
  CHECK(text.str().find("controlled 3/3 (100 %)") != std::string::npos);
  CHECK(text.str().find("controlled 2/3 (67 %)") != std::string::npos);
  CHECK(text.str().find("seed 2: completed, vehicle NOT controlled") != std::string::npos);
  const YAML::Node j = YAML::Load(sweep_json(r));
  REQUIRE(j["runs"].size() == 6);
  CHECK(j["runs"][4]["seed"].as<int>() == 2);
  CHECK(j["runs"][4]["exit_code"].as<int>() == kRunNotControlled);
  CHECK(j["sets"][1]["controlled_rate"].as<double>() == Approx(2.0 / 3.0));
  CHECK(j["sets"][1]["percentiles"]["max_abs_phi_deg"]["p50"].as<double>() == 22.0);
  CHECK(j["sets"][0]["overrides"]["model"].as<std::string>() == "a");
  const std::string csv = sweep_csv(r);
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);
  CHECK(csv.find("2,\"model=b\",2,1,\"completed, vehicle NOT controlled\",0,0") != std::string::npos);
}

namespace {

/// Writes `ticks` RIG_CLOCK events 1 ms of simulated time apart (with a HEARTBEAT before the
/// first and a TRUTH-like event after each) as fast as it can, returns the log's event times.
std::vector<int64_t> record_ticks(const std::string& file, LogStamps stamps, int ticks) {
  RunMonitor monitor(MonitorConfig{});
  {
    Recorder recorder(file, monitor, stamps);
    const std::vector<unsigned char> other(16, 0);
    recorder.record(nimble::contract::channels::kHeartbeat, other.data(), static_cast<int>(other.size()), 0);
    for (int k = 0; k < ticks; ++k) {
      nimble::rig_clock_t tick{};
      tick.step = k;
      tick.sim_time_ns = 1000000LL * k;
      tick.utime = tick.sim_time_ns / 1000;
      const std::vector<unsigned char> bytes = nimble::test::encoded(tick);
      recorder.record(nimble::contract::channels::kRigClock, bytes.data(), static_cast<int>(bytes.size()), 0);
      recorder.record(nimble::contract::channels::kTruth, other.data(), static_cast<int>(other.size()), 0);
    }
  }
  lcm::LogFile log(file, "r");
  std::vector<int64_t> t;
  while (const lcm::LogEvent* ev = log.readNextEvent()) t.push_back(ev->timestamp);
  return t;
}

}  // namespace

TEST_CASE("recorder: lockstep logs carry simulated time, real-time logs the wall clock", "[launcher]") {
  const std::string file = nimble::test::scratch_file("recorder", "recorder.lcmlog");
  const int ticks = 3001;  // 3 s of simulated time, written in a few milliseconds
  const std::vector<int64_t> sim = record_ticks(file, LogStamps::kSimulated, ticks);
  REQUIRE(sim.size() == static_cast<std::size_t>(1 + 2 * ticks));
  CHECK(std::is_sorted(sim.begin(), sim.end()));
  // From the first tick to the last: exactly the simulated 3 s; each event after a tick
  // carries that tick's time.
  CHECK(sim.back() - sim[1] == 3000000);
  CHECK(sim[2] == sim[1]);
  CHECK(sim[4] - sim[2] == 1000);
  const std::vector<int64_t> wall = record_ticks(file, LogStamps::kWallClock, ticks);
  REQUIRE(wall.size() == sim.size());
  CHECK(std::is_sorted(wall.begin(), wall.end()));
  CHECK(wall.back() - wall[1] < 1000000);  // the wall clock: far less than the simulated 3 s
  std::remove(file.c_str());
}

namespace {

std::vector<unsigned char> tick_bytes(int64_t sim_time_ns) {
  nimble::rig_clock_t tick{};
  tick.step = sim_time_ns / 1000000;
  tick.sim_time_ns = sim_time_ns;
  tick.utime = sim_time_ns / 1000;
  return nimble::test::encoded(tick);
}

}  // namespace

TEST_CASE("recorder: simulated time begins at the receipt of the first tick or lockstep truth, not at its writing",
          "[launcher]") {
  const std::string file = nimble::test::scratch_file("recorder", "recorder_late.lcmlog");
  RunMonitor monitor(MonitorConfig{});
  const int64_t received_ns = nimble::transport::monotonic_ns();
  const auto record = [&](const std::string& channel, const std::vector<unsigned char>& bytes, int64_t at_ns) {
    Recorder recorder(file, monitor, LogStamps::kSimulated);
    const std::vector<unsigned char> other(16, 0);
    recorder.record(nimble::contract::channels::kHeartbeat, other.data(), static_cast<int>(other.size()), received_ns);
    std::this_thread::sleep_for(std::chrono::milliseconds(30));  // the recorder falls behind
    recorder.record(channel, bytes.data(), static_cast<int>(bytes.size()), at_ns);
    const std::vector<unsigned char> next = tick_bytes(1000000);
    recorder.record(nimble::contract::channels::kRigClock, next.data(), static_cast<int>(next.size()), at_ns + 5000000);
  };
  const auto times = [&] {
    lcm::LogFile log(file, "r");
    std::vector<int64_t> t;
    while (const lcm::LogEvent* ev = log.readNextEvent()) t.push_back(ev->timestamp);
    return t;
  };
  SECTION("the first tick, received 40 us after a heartbeat") {
    record(nimble::contract::channels::kRigClock, tick_bytes(0), received_ns + 40000);
    const std::vector<int64_t> t = times();
    REQUIRE(t.size() == 3);
    CHECK(t[1] - t[0] >= 39);  // the receipt times (in whole microseconds)
    CHECK(t[1] - t[0] <= 41);
    CHECK(t[2] - t[1] == 1000);  // then simulated time, however late the tick came
  }
  SECTION("the master's first truth, which goes out before its tick") {
    nimble::truth_state_t truth{};
    truth.utime = 0;
    truth.step = 0;
    record(nimble::contract::channels::kTruth, nimble::test::encoded(truth), received_ns + 40000);
    const std::vector<int64_t> t = times();
    REQUIRE(t.size() == 3);
    CHECK(t[1] - t[0] >= 39);
    CHECK(t[1] - t[0] <= 41);
    CHECK(t[2] - t[1] == 1000);  // the tick of 1 ms, received 5 ms after the truth
  }
  std::remove(file.c_str());
}

namespace {

TimingSummary loops(int64_t count, int64_t overruns) {
  TimingSummary t;
  t.loop_count = count;
  t.overruns = overruns;
  return t;
}

}  // namespace

TEST_CASE("timing verdict: fractions against the thresholds, the worst named", "[launcher]") {
  JudgeConfig jc;  // 1 % late, 1 % overruns
  std::map<std::string, TimingSummary> timing;
  timing["plant"] = loops(6000, 30);                                                    // 0.5 %
  timing["plant"].received[nimble::contract::channels::kActuatorCommand] = {3000, 15};  // 0.5 %
  timing["controller"] = loops(3000, 0);
  timing["controller"].received[nimble::contract::channels::kEstimate] = {3000, 3};  // 0.1 %

  SECTION("below both limits: ok, and the worst still named") {
    const TimingVerdict v = judge_timing(timing, jc, true);
    CHECK(v.judged);
    CHECK_FALSE(v.degraded);
    CHECK(v.worst == "plant");
    CHECK(v.text.find("real-time ok") == 0);
  }
  SECTION("late commands above the limit: degraded, naming the receiver and the publisher") {
    timing["plant"].received[nimble::contract::channels::kActuatorCommand] = {3000, 1170};  // 39 %
    const TimingVerdict v = judge_timing(timing, jc, true);
    CHECK(v.degraded);
    CHECK(v.worst == "plant");
    CHECK(v.worst_fraction == Approx(0.39));
    CHECK(v.text.find("real-time degraded: 39.0 % of ACTUATOR_CMD arrived late at plant") == 0);
    CHECK(v.text.find("published by controller") != std::string::npos);
    // The run's result says so; --strict-timing makes it an exit code.
    FlightSummary f = calm_flight();
    const Verdict lenient = judge_run(f, jc, false, "", v, false);
    CHECK(lenient.exit_code == kRunOk);
    CHECK(lenient.text.find("real-time degraded") == 0);
    const Verdict strict = judge_run(f, jc, false, "", v, true);
    CHECK(strict.exit_code == kRunTimingDegraded);
    // A worse outcome keeps its own code and text.
    CHECK(judge_run(f, jc, false, "plant died", v, true).exit_code == kRunFailed);
  }
  SECTION("overruns above the limit: degraded, naming the process") {
    timing["controller"] = loops(3000, 300);
    const TimingVerdict v = judge_timing(timing, jc, true);
    CHECK(v.degraded);
    CHECK(v.worst == "controller");
    CHECK(v.text.find("controller overran 10.0 %") != std::string::npos);
  }
  SECTION("a stricter threshold turns the same run degraded") {
    jc.max_overrun_fraction = 0.001;
    CHECK(judge_timing(timing, jc, true).degraded);
  }
  SECTION("lockstep and in process are not judged") {
    timing["plant"] = loops(6000, 6000);
    const TimingVerdict v = judge_timing(timing, jc, false);
    CHECK_FALSE(v.judged);
    CHECK_FALSE(v.degraded);
    CHECK(judge_run(calm_flight(), jc, false, "", v, true).exit_code == kRunOk);
  }
}
