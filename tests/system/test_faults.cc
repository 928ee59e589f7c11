// Fault tests (label `fault`): the scenario's `faults` section injects each kind of fault at its
// publisher, and each has a named outcome: the FAULT codes raised and by whom, the estimator's
// and the controller's reaction, and the run's verdict and exit code. Most fly hover in lockstep
// (deterministic, fast); the watchdogs that need a wall clock (a hung process) fly in real time.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"

#include "../support/rig_runs.h"

namespace ch = nimble::contract::channels;
using nimble::fault_event_t;
using nimble::test::rig_run;
using nimble::test::rig_run_background;
using nimble::test::RunResult;
using nimble::test::slurp;
using nimble::test::wait_exit_code;
using nimble::test::wait_for_running;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
constexpr int kExitOk = 0, kExitFailed = 3, kExitBadInput = 2, kExitFailsafe = 5;

/// Flies hover for `duration_s` in lockstep (on the estimator) with `faults` (a YAML flow list).
RunResult fly(const std::string& tag, const std::string& faults, double duration_s = 3.0,
              const std::string& extra = "") {
  const std::string dir = nimble::test::scratch_dir("faults_" + tag);
  return rig_run(
      kConfigs + "hover.yaml", dir,
      "--clock lockstep --set duration_s=" + std::to_string(duration_s) + " --set 'faults=" + faults + "' " + extra);
}

/// The faults of a run summary with `code`, as "process: message" lines.
std::vector<YAML::Node> faults_with(const YAML::Node& summary, int code) {
  std::vector<YAML::Node> out;
  for (const auto& f : summary["faults"]) {
    if (f["code"].as<int>() == code) out.push_back(f);
  }
  return out;
}

/// The first fault with `code` from `process`; a null node if none.
YAML::Node first_fault(const YAML::Node& summary, int code, const std::string& process) {
  for (const auto& f : faults_with(summary, code)) {
    if (f["process"].as<std::string>() == process) return f;
  }
  return YAML::Node();
}

/// The injected fault's announcement from its publisher (began, then ended if it did).
void check_announced(const YAML::Node& summary, const std::string& publisher, const std::string& target) {
  const YAML::Node f = first_fault(summary, fault_event_t::CODE_FAULT_INJECTED, publisher);
  REQUIRE(f);
  CHECK(f["channel"].as<std::string>() == target);
  CHECK(f["severity"].as<int>() == fault_event_t::SEVERITY_INFO);
  CHECK(f["message"].as<std::string>().find("began") != std::string::npos);
}

/// Simulated time [s] of the first CONTROLLER_STATUS with failsafe set in a log; -1 if none.
double failsafe_time_s(const std::string& log_path) {
  lcm::LogFile log(log_path, "r");
  REQUIRE(log.good());
  while (const lcm::LogEvent* e = log.readNextEvent()) {
    if (e->channel != ch::kControllerStatus) continue;
    nimble::controller_status_t st;
    if (st.decode(e->data, 0, e->datalen) != e->datalen) continue;
    if (st.failsafe) return 1e-6 * static_cast<double>(st.utime);
  }
  return -1.0;
}

std::string dir_of(const std::string& tag) { return nimble::test::scratch_path("faults_" + tag); }

/// The second run `b` (tag `tag_b`) of the faulted run tagged `tag_a`, same seed: the fault's
/// random choices are drawn from the seed at the publisher, so it lost the same `drops` messages
/// on `channel` and flew byte-identical TRUTH.
void check_same_again(const std::string& tag_a, const RunResult& b, const std::string& tag_b,
                      const std::string& channel, int drops) {
  REQUIRE(b.summary);
  CHECK(b.summary["channels"][channel]["drops"].as<int>() == drops);
  CHECK(nimble::test::differing(nimble::test::truth_payloads(dir_of(tag_a) + "/run.lcmlog"),
                                nimble::test::truth_payloads(dir_of(tag_b) + "/run.lcmlog")) == 0);
}

}  // namespace

TEST_CASE("off: ESTIMATE stops at 1 s, the controller takes its failsafe 50 ms later", "[fault]") {
  const RunResult r = fly("off_estimate", "[{target: ESTIMATE, kind: off, start_s: 1.0}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitFailsafe);
  check_announced(r.summary, "estimator", ch::kEstimate);
  const YAML::Node stale = first_fault(r.summary, fault_event_t::CODE_INPUT_STALE, "controller");
  const YAML::Node failsafe = first_fault(r.summary, fault_event_t::CODE_FAILSAFE, "controller");
  REQUIRE(stale);
  REQUIRE(failsafe);
  CHECK(failsafe["severity"].as<int>() == fault_event_t::SEVERITY_ERROR);
  CHECK(failsafe["rig_time_s"].as<double>() == Approx(1.05).margin(0.01));
  CHECK(r.summary["result"].as<std::string>().find("failsafe") != std::string::npos);
  // From then on every status says so; before it none did.
  CHECK(failsafe_time_s(dir_of("off_estimate") + "/run.lcmlog") == Approx(1.05).margin(0.01));
}

TEST_CASE("off: ACTUATOR_CMD stops for 0.3 s, the plant holds its safe state on COMMAND_TIMEOUT", "[fault]") {
  const RunResult r = fly("off_cmd", "[{target: ACTUATOR_CMD, kind: off, start_s: 1.0, duration_s: 0.3}]");
  INFO(r.output);
  REQUIRE(r.summary);
  check_announced(r.summary, "controller", ch::kActuatorCommand);
  const YAML::Node timeout = first_fault(r.summary, fault_event_t::CODE_COMMAND_TIMEOUT, "plant");
  REQUIRE(timeout);
  CHECK(timeout["rig_time_s"].as<double>() > 1.0);
  CHECK(timeout["rig_time_s"].as<double>() < 1.3);
  // No estimator or controller fault: the estimate kept coming, the controller never went stale.
  CHECK(faults_with(r.summary, fault_event_t::CODE_FAILSAFE).empty());
}

TEST_CASE("stuck: a frozen IMU is named SENSOR_STUCK by the estimator, and the controller takes its failsafe",
          "[fault]") {
  const RunResult r = fly("stuck_imu", "[{target: IMU, kind: stuck, start_s: 1.0}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitFailsafe);
  check_announced(r.summary, "plant", ch::kImu);
  const YAML::Node stuck = first_fault(r.summary, fault_event_t::CODE_SENSOR_STUCK, "estimator");
  REQUIRE(stuck);
  CHECK(stuck["severity"].as<int>() == fault_event_t::SEVERITY_ERROR);
  // 50 identical samples at 512 Hz: detected about 0.1 s after the IMU froze.
  CHECK(stuck["rig_time_s"].as<double>() == Approx(1.1).margin(0.02));
  const YAML::Node failsafe = first_fault(r.summary, fault_event_t::CODE_FAILSAFE, "controller");
  REQUIRE(failsafe);
  CHECK(failsafe["rig_time_s"].as<double>() > stuck["rig_time_s"].as<double>());
}

TEST_CASE("garbage: malformed MOCAP_POSE bytes are counted and left out, the run flies on", "[fault]") {
  const RunResult r = fly("garbage_bytes", "[{target: MOCAP_POSE, kind: garbage, start_s: 1.0, duration_s: 0.5}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitOk);
  check_announced(r.summary, "mocap", ch::kMocapPose);
  // 0.5 s at 200 Hz: about 100 poses replaced by bytes that do not decode.
  const int malformed = r.summary["channels"][ch::kMocapPose]["malformed"].as<int>();
  CHECK(malformed >= 95);
  CHECK(malformed <= 105);
  CHECK(first_fault(r.summary, fault_event_t::CODE_MESSAGE_MALFORMED, "estimator"));
  CHECK(r.summary["controlled"].as<bool>());
}

TEST_CASE("garbage nan: non-finite poses are refused by the estimator as malformed, the run flies on", "[fault]") {
  const RunResult r =
      fly("garbage_nan", "[{target: MOCAP_POSE, kind: garbage, start_s: 1.0, duration_s: 0.5, params: {mode: nan}}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitOk);
  const YAML::Node m = first_fault(r.summary, fault_event_t::CODE_MESSAGE_MALFORMED, "estimator");
  REQUIRE(m);
  CHECK(m["message"].as<std::string>().find("non-finite") != std::string::npos);
  CHECK(r.summary["controlled"].as<bool>());
  CHECK(std::isfinite(r.summary["estimator"]["phi_rms_deg"].as<double>()));
}

TEST_CASE("wrong: a 23 deg roll bias on the motion capture makes the estimator declare ESTIMATOR_DIVERGED", "[fault]") {
  // quaternion x + 0.2: about 23 deg of roll; every attitude innovation fails the gate.
  const RunResult r = fly("wrong_pose",
                          "[{target: MOCAP_POSE, kind: wrong, start_s: 1.0, params: "
                          "{field: \"quaternion_wxyz[1]\", bias: 0.2}}]");
  INFO(r.output);
  REQUIRE(r.summary);
  const YAML::Node d = first_fault(r.summary, fault_event_t::CODE_ESTIMATOR_DIVERGED, "estimator");
  REQUIRE(d);
  CHECK(d["rig_time_s"].as<double>() > 1.0);
  CHECK(d["rig_time_s"].as<double>() < 1.3);
  // It publishes no more estimates: the controller's failsafe follows.
  CHECK(r.exit_code == kExitFailsafe);
  CHECK(first_fault(r.summary, fault_event_t::CODE_FAILSAFE, "controller"));
}

TEST_CASE("slow: MOCAP_POSE at a quarter of its rate arrives without gaps and the run flies on", "[fault]") {
  const RunResult r = fly("slow_pose", "[{target: MOCAP_POSE, kind: slow, start_s: 1.0, params: {divisor: 4}}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitOk);
  const YAML::Node pose = r.summary["channels"][ch::kMocapPose];
  // 1 s at 200 Hz, then 2 s at 50 Hz; a slower sensor leaves no gap in its sequence.
  CHECK(pose["count"].as<int>() == Approx(300).margin(5));
  CHECK(pose["drops"].as<int>() == 0);
  CHECK(r.summary["controlled"].as<bool>());
}

TEST_CASE("delayed: MOCAP_POSE 150 ms late is outside the EKF's window: MEASUREMENT_OUT_OF_WINDOW", "[fault]") {
  const RunResult r = fly(
      "delayed_pose", "[{target: MOCAP_POSE, kind: delayed, start_s: 1.0, duration_s: 1.0, params: {delay_ms: 150}}]");
  INFO(r.output);
  REQUIRE(r.summary);
  const YAML::Node w = first_fault(r.summary, fault_event_t::CODE_MEASUREMENT_OUT_OF_WINDOW, "estimator");
  REQUIRE(w);
  CHECK(w["rig_time_s"].as<double>() == Approx(1.15).margin(0.02));
  CHECK(w["message"].as<std::string>().find("late") != std::string::npos);
  // The IMU keeps the estimate going: the vehicle stays controlled.
  CHECK(r.exit_code == kExitOk);
  CHECK(r.summary["controlled"].as<bool>());
}

TEST_CASE("intermittent: ACTUATOR_CMD lost 30 % of the time shows as drops, the same in every run", "[fault]") {
  const std::string faults =
      "[{target: ACTUATOR_CMD, kind: intermittent, start_s: 1.0, duration_s: 1.0, params: {probability: 0.3}}]";
  const RunResult a = fly("intermittent_a", faults);
  INFO(a.output);
  REQUIRE(a.summary);
  CHECK(a.exit_code == kExitOk);
  // 1 s of 512 Hz commands, 30 % lost: Binomial(512, 0.3) is 154 +- 10.
  const int drops = a.summary["channels"][ch::kActuatorCommand]["drops"].as<int>();
  CHECK(drops > 154 - 50);
  CHECK(drops < 154 + 50);
  CHECK(a.summary["controlled"].as<bool>());
  check_same_again("intermittent_a", fly("intermittent_b", faults), "intermittent_b", ch::kActuatorCommand, drops);
}

TEST_CASE("faults section: a bad entry is refused before anything starts, named with its key", "[fault]") {
  struct Bad {
    std::string faults, expected;
  };
  const std::vector<Bad> cases = {
      {"[{target: GPS, kind: off, start_s: 1}]", "faults[0].target"},
      {"[{target: IMU, kind: bus_off, start_s: 1}]", "faults[0].kind"},
      {"[{target: IMU, kind: slow, start_s: 1, params: {divisor: 1}}]", "faults[0].params.divisor"},
      {"[{target: IMU, kind: off, start_s: 9}]", "faults[0].start_s"},
      {"[{target: IMU, kind: off, start_s: 1, params: {delay_ms: 5}}]", "delay_ms"},
      {"[{target: IMU, kind: wrong, start_s: 1, params: {field: gps, bias: 1}}]", "no value field 'gps'"},
      {"[{target: CAN, kind: loss, start_s: 1, params: {probability: 0.1}}]", "actuator_link: can"},
  };
  {
    const RunResult r = fly("bad", "[{target: ACTUATOR_CMD, kind: off, start_s: 1}]", 3.0, "--set actuator_link=can");
    CHECK(r.exit_code == kExitBadInput);
    CHECK(r.output.find("use target CAN") != std::string::npos);
  }
  for (const auto& c : cases) {
    INFO(c.faults);
    const RunResult r = fly("bad", c.faults);
    CHECK(r.exit_code == kExitBadInput);
    CHECK(r.output.find(c.expected) != std::string::npos);
  }
}

TEST_CASE("watchdog: a process that hangs without exiting is named HEARTBEAT_LOST by the launcher", "[fault]") {
  const std::string dir = nimble::test::scratch_dir("faults_hung");
  const pid_t rig = rig_run_background(kConfigs + "hover.yaml", dir,
                                       "--clock realtime --set duration_s=8 --set run.heartbeat_timeout_s=1.0");
  const pid_t mocap = wait_for_running(rig, "nimble_mocap", dir + "/run.lcmlog");
  REQUIRE(mocap > 0);
  ::kill(mocap, SIGSTOP);  // alive, silent
  const int code = wait_exit_code(rig);
  ::kill(mocap, SIGCONT);
  const std::string out = slurp(dir + "/out.txt");
  INFO(out);
  CHECK(code == kExitFailed);
  CHECK(out.find("HEARTBEAT_LOST") != std::string::npos);
  CHECK(out.find("process 'mocap'") != std::string::npos);
  const YAML::Node s = YAML::LoadFile(dir + "/summary.json");
  const YAML::Node lost = first_fault(s, fault_event_t::CODE_HEARTBEAT_LOST, "launcher");
  REQUIRE(lost);
  CHECK(lost["severity"].as<int>() == fault_event_t::SEVERITY_FATAL);
  CHECK(lost["message"].as<std::string>().find("mocap") != std::string::npos);
  // Detected about a second after the last heartbeat, long before the run's 8 s.
  CHECK(s["sim_time_s"].as<double>() < 6.0);
}

TEST_CASE("external process: one started by hand with the run's scenario joins the run, another scenario is refused",
          "[fault]") {
  const std::string bin_dir = std::filesystem::path(RIG_BIN).parent_path().string();
  const auto run_with_external = [&](const std::string& tag, bool same_scenario) {
    const std::string dir = nimble::test::scratch_dir("faults_external_" + tag);
    const pid_t rig = rig_run_background(
        kConfigs + "hover.yaml", dir, "--clock lockstep --set duration_s=2 --set run.external_processes=[controller]");
    // The launcher writes the resolved scenario before it starts anyone.
    const std::string resolved = dir + "/run.lcmlog.scenario.yaml";
    for (int i = 0; i < 200 && !std::filesystem::exists(resolved); ++i) ::usleep(50000);
    REQUIRE(std::filesystem::exists(resolved));
    ::usleep(300000);
    const std::string scenario = same_scenario ? resolved : kConfigs + "hover.yaml";
    const std::string cmd = "nsenter -t " + std::to_string(rig) + " -n " + bin_dir +
                            "/nimble_controller --name controller --scenario " + scenario +
                            " --lcm-url 'udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608' > " + dir +
                            "/controller.out 2>&1 &";
    REQUIRE(std::system(cmd.c_str()) == 0);
    const int code = wait_exit_code(rig);
    std::system(("pkill -f 'nimble_controller --name controller --scenario " + scenario + "'").c_str());
    return std::make_pair(code, slurp(dir + "/out.txt"));
  };
  SECTION("the same scenario: the run flies") {
    const auto [code, out] = run_with_external("same", true);
    INFO(out);
    CHECK(code == kExitOk);
    // The launcher did not start it, it knows it from its heartbeat, and it stopped with the run.
    const YAML::Node s = YAML::LoadFile(nimble::test::scratch_path("faults_external_same") + "/summary.json");
    CHECK(s["processes"]["controller"]["pid"].as<int>() > 0);
    CHECK(s["processes"]["controller"]["exit_code"].as<int>() == 0);
    CHECK(nimble::test::channel_counts(nimble::test::scratch_path("faults_external_same") + "/run.lcmlog")
              .at(ch::kActuatorCommand) == 1024);
  }
  SECTION("another scenario: refused, naming the process and both digests") {
    const auto [code, out] = run_with_external("other", false);
    INFO(out);
    CHECK(code == kExitBadInput);
    CHECK(out.find("process 'controller'") != std::string::npos);
    CHECK(out.find("started with another scenario") != std::string::npos);
  }
}

TEST_CASE("external process: one started after the run's model file changed under the same path is refused",
          "[fault]") {
  // The run flies a copy of set 1's model; after the launcher has read it (and written the
  // resolved scenario), the copy changes. A process started now with the run's own resolved
  // scenario reads the changed model: its digest is not the run's, and the launcher refuses it.
  const std::string bin_dir = std::filesystem::path(RIG_BIN).parent_path().string();
  const std::string dir = nimble::test::scratch_dir("faults_external_model_changed");
  const std::string model = dir + "/model.yaml";
  std::filesystem::copy_file(kConfigs + "models/nimble_lateral_set1.yaml", model);
  {
    // The copy's vehicle is named relative to the model file: name the shipped one absolutely.
    std::ifstream in(model);
    std::stringstream text;
    text << in.rdbuf();
    std::string s = text.str();
    const std::string from = "vehicle: ../vehicles/", to = "vehicle: " + kConfigs + "vehicles/";
    s.replace(s.find(from), from.size(), to);
    std::ofstream(model) << s;
  }
  const pid_t rig = rig_run_background(
      kConfigs + "hover.yaml", dir,
      "--clock lockstep --set duration_s=2 --set model=" + model + " --set run.external_processes=[controller]");
  const std::string resolved = dir + "/run.lcmlog.scenario.yaml";
  for (int i = 0; i < 200 && !std::filesystem::exists(resolved); ++i) ::usleep(50000);
  REQUIRE(std::filesystem::exists(resolved));
  ::usleep(300000);
  std::ofstream(model, std::ios::app) << "# changed during the run\n";
  const std::string cmd = "nsenter -t " + std::to_string(rig) + " -n " + bin_dir +
                          "/nimble_controller --name controller --scenario " + resolved +
                          " --lcm-url 'udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608' > " + dir +
                          "/controller.out 2>&1 &";
  REQUIRE(std::system(cmd.c_str()) == 0);
  const int code = wait_exit_code(rig);
  std::system(("pkill -f 'nimble_controller --name controller --scenario " + resolved + "'").c_str());
  const std::string out = slurp(dir + "/out.txt");
  INFO(out);
  CHECK(code == kExitBadInput);
  CHECK(out.find("process 'controller'") != std::string::npos);
  CHECK(out.find("started with another scenario") != std::string::npos);
  CHECK(out.find("change no model, manoeuvre or vehicle file during a run") != std::string::npos);
}

TEST_CASE("watchdogs stay quiet in nominal flights: no divergence, stuck IMU or failsafe over 16 seeded runs",
          "[fault]") {
  // The false-alarm side of the watchdogs: flights without faults, in process (fast), two
  // manoeuvres on the estimator times 8 seeds; the gate decisions are counted to show the
  // filter's nominal rejection rate against the 0.001 the divergence threshold assumes.
  int64_t accepted = 0, rejected = 0;
  for (const std::string scenario : {"id_doublet_train_fast", "cl_doublet_train_slow"}) {
    for (int seed = 1; seed <= 8; ++seed) {
      const std::string dir = nimble::test::scratch_dir("faults_quiet");
      const RunResult r =
          rig_run(kConfigs + scenario + ".yaml", dir, "--clock inprocess --seed " + std::to_string(seed));
      INFO(scenario << " seed " << seed << "\n" << r.output);
      REQUIRE(r.summary);
      CHECK(r.exit_code == kExitOk);
      const std::vector<int> watchdog_codes = {fault_event_t::CODE_ESTIMATOR_DIVERGED, fault_event_t::CODE_SENSOR_STUCK,
                                               fault_event_t::CODE_FAILSAFE, fault_event_t::CODE_INPUT_STALE};
      for (const int code : watchdog_codes) {
        CHECK(faults_with(r.summary, code).empty());
      }
      accepted += r.summary["estimator"]["poses_accepted"].as<int64_t>();
      rejected += r.summary["estimator"]["poses_rejected"].as<int64_t>();
    }
  }
  const double rate = static_cast<double>(rejected) / static_cast<double>(accepted + rejected);
  std::printf("nominal gate rejections: %lld of %lld (%.2e; the divergence threshold assumes 1e-3)\n",
              static_cast<long long>(rejected), static_cast<long long>(accepted + rejected), rate);
  CHECK(accepted > 20000);  // 8 x (6 s + 9 s) at 200 Hz, less the frames the emulated tracking loses
  CHECK(rate < 1e-3);
}

namespace {

/// Flies hover over the CAN link in process (the bridge's code on an in-process frame bus) with
/// `faults`.
RunResult fly_can(const std::string& tag, const std::string& faults) {
  const std::string dir = nimble::test::scratch_dir("faults_" + tag);
  return rig_run(kConfigs + "hover.yaml", dir,
                 "--clock inprocess --set duration_s=3 --set actuator_link=can --set 'faults=" + faults + "'");
}

}  // namespace

TEST_CASE("CAN loss: frames lost with p = 0.2 lose whole commands as drops, the same in every run", "[fault]") {
  const std::string faults = "[{target: CAN, kind: loss, start_s: 1.0, duration_s: 1.0, params: {probability: 0.2}}]";
  const RunResult a = fly_can("can_loss_a", faults);
  INFO(a.output);
  REQUIRE(a.summary);
  CHECK(a.exit_code == kExitOk);
  check_announced(a.summary, "can_flight", "CAN");
  // A command is two frames: 1 - 0.8^2 = 36 % of 512 commands lost, Binomial sd 11.
  const int drops = a.summary["channels"][ch::kActuatorCommandCan]["drops"].as<int>();
  CHECK(drops > 184 - 55);
  CHECK(drops < 184 + 55);
  CHECK(a.summary["channels"][ch::kActuatorCommand]["drops"].as<int>() == 0);  // the loss is the link's
  CHECK(a.summary["controlled"].as<bool>());
  check_same_again("can_loss_a", fly_can("can_loss_b", faults), "can_loss_b", ch::kActuatorCommandCan, drops);
}

TEST_CASE("CAN corrupt: a flipped bit fails the frame's CRC, both sides name it MESSAGE_MALFORMED", "[fault]") {
  const RunResult r = fly_can(
      "can_corrupt", "[{target: CAN, kind: corrupt, start_s: 1.0, duration_s: 1.0, params: {probability: 0.1}}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitOk);
  for (const std::string side : {"can_rig", "can_flight"}) {
    const YAML::Node m = first_fault(r.summary, fault_event_t::CODE_MESSAGE_MALFORMED, side);
    REQUIRE(m);
    CHECK(m["message"].as<std::string>().find("bad_checksum") != std::string::npos);
  }
  // 1 - 0.9^2 = 19 % of 512 commands, sd 9.
  const int drops = r.summary["channels"][ch::kActuatorCommandCan]["drops"].as<int>();
  CHECK(drops > 97 - 45);
  CHECK(drops < 97 + 45);
  CHECK(r.summary["controlled"].as<bool>());
}

TEST_CASE("CAN bus_off: both controllers report bus-off, the plant holds its safe state and resumes after", "[fault]") {
  const RunResult r = fly_can("can_bus_off", "[{target: CAN, kind: bus_off, start_s: 1.0, duration_s: 0.3}]");
  INFO(r.output);
  REQUIRE(r.summary);
  CHECK(r.exit_code == kExitOk);
  for (const std::string side : {"can_rig", "can_flight"}) {
    const YAML::Node e = first_fault(r.summary, fault_event_t::CODE_CAN_ERROR_FRAME, side);
    REQUIRE(e);
    CHECK(e["severity"].as<int>() == fault_event_t::SEVERITY_ERROR);
    CHECK(e["message"].as<std::string>().find("bus-off") != std::string::npos);
  }
  // No command for command_timeout_s (0.1 s): the safe state at 1.1 s, left once commands resume.
  std::vector<double> times;
  for (const auto& f : faults_with(r.summary, fault_event_t::CODE_COMMAND_TIMEOUT))
    times.push_back(f["rig_time_s"].as<double>());
  REQUIRE(times.size() == 2);
  CHECK(times[0] == Approx(1.1).margin(0.005));
  CHECK(times[1] > 1.3);
  CHECK(times[1] < 1.35);
  // 0.3 s of commands, and the few after it whose counters look stale to the receiver.
  const int drops = r.summary["channels"][ch::kActuatorCommandCan]["drops"].as<int>();
  CHECK(drops >= 154);
  CHECK(drops <= 154 + 8);
}
