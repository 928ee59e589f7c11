// System tests: the real executables, launched by `rig run` in a private network
// namespace (the launcher creates it), with short scenarios. They wait on the launcher's
// exit and on what it records, never on fixed sleeps of the rig itself.

#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/controller_status_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/timing_health_t.hpp>
#include <nimble/truth_state_t.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"

#include "../support/rig_runs.h"

namespace fs = std::filesystem;
using namespace nimble::contract::channels;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

using nimble::test::channel_counts;
using nimble::test::child_named;
using nimble::test::decode_channel;
using nimble::test::differing;
using nimble::test::rig_run;
using nimble::test::rig_run_background;
using nimble::test::RunResult;
using nimble::test::slurp;
using nimble::test::truth_payloads;
using nimble::test::wait_exit_code;
using nimble::test::wait_for_running;

/// A fresh directory for one test's logs.
std::string scratch_dir(const std::string& tag) { return nimble::test::scratch_dir("system_" + tag); }

/// TRUTH of a log by its time stamp [us].
std::map<int64_t, nimble::truth_state_t> truth_by_utime(const std::string& log_path) {
  std::map<int64_t, nimble::truth_state_t> truth;
  for (const auto& t : decode_channel<nimble::truth_state_t>(log_path, kTruth)) truth[t.utime] = t;
  return truth;
}

}  // namespace

TEST_CASE("identification doublet train in lockstep: controlled, back to hover, Table 9.4 ranges, all rates",
          "[system]") {
  const std::string dir = scratch_dir("idtrain");
  const RunResult r = rig_run(kConfigs + "id_doublet_train_fast.yaml", dir, "--clock lockstep");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const YAML::Node& s = r.summary;
  CHECK(s["controlled"].as<bool>());
  CHECK(s["returned_to_hover"].as<bool>());
  CHECK(s["sim_time_s"].as<double>() == Approx(6.0).margin(0.002));
  // Thesis Table 9.4, identification set 1: p 12.06 rad/s, v 1.17 m/s, phi 0.89 rad.
  const double p = s["ranges"]["p"].as<double>(), v = s["ranges"]["v"].as<double>(),
               phi = s["ranges"]["phi"].as<double>();
  CHECK(p > 12.06 / 2);
  CHECK(p < 12.06 * 2);
  CHECK(v > 1.17 / 2);
  CHECK(v < 1.17 * 2);
  CHECK(phi > 0.89 / 2);
  CHECK(phi < 0.89 * 2);
  // Every stream channel at its rate in simulated time, nothing dropped.
  for (const std::string& ch : {kTruth, kActuatorCommand, kActuatorFeedback, kAttitudeSetpoint, kControllerStatus,
                                kRigClock, kStepAck, kImu, kMocapPose, kEstimate}) {
    INFO(ch);
    const YAML::Node c = s["channels"][ch];
    REQUIRE(c);
    CHECK(c["rate_hz"].as<double>() == Approx(c["expected_hz"].as<double>()).epsilon(0.01));
    CHECK(c["drops"].as<int>() == 0);
    CHECK(c["malformed"].as<int>() == 0);
  }
  // The log replays: TRUTH at 1 kHz for 6 s.
  const auto counts = channel_counts(dir + "/run.lcmlog");
  CHECK(counts.at(kTruth) == 6001);
  CHECK(counts.at(kActuatorCommand) == 3072);
  // The resolved scenario is kept next to the log.
  CHECK(fs::exists(dir + "/run.lcmlog.scenario.yaml"));
}

TEST_CASE("two lockstep runs give bit-identical truth", "[system]") {
  const std::string a = scratch_dir("det_a"), b = scratch_dir("det_b");
  const std::string scenario = kConfigs + "ol_doublet_6hz_fast.yaml";
  // The second run shares the machine with a busy loop: load must not change the truth.
  std::atomic<bool> busy{true};
  const RunResult ra = rig_run(scenario, a, "--clock lockstep --set duration_s=3");
  std::thread hog([&] {
    volatile double x = 0;
    while (busy) x = x + 1.0;
  });
  const RunResult rb = rig_run(scenario, b, "--clock lockstep --set duration_s=3");
  busy = false;
  hog.join();
  REQUIRE(ra.exit_code == 0);
  REQUIRE(rb.exit_code == 0);
  const auto ta = truth_payloads(a + "/run.lcmlog"), tb = truth_payloads(b + "/run.lcmlog");
  REQUIRE(ta.size() == 3001);
  CHECK(differing(ta, tb) == 0);
  // The flight is not trivially identical: the vehicle moved.
  CHECK(ra.summary["max_abs"]["phi"].as<double>() > 0.1);
}

TEST_CASE("a short real-time run holds its rates", "[system]") {
  const std::string dir = scratch_dir("realtime");
  const RunResult r = rig_run(kConfigs + "hover.yaml", dir, "--clock realtime --set duration_s=2");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const double wall = r.summary["wall_time_s"].as<double>();
  CHECK(wall == Approx(2.0).margin(0.3));
  for (const std::string& ch : {kTruth, kActuatorCommand, kActuatorFeedback}) {
    INFO(ch);
    const YAML::Node c = r.summary["channels"][ch];
    CHECK(c["rate_hz"].as<double>() == Approx(c["expected_hz"].as<double>()).epsilon(0.02));
    CHECK(c["drops"].as<int>() == 0);
  }
  CHECK(r.summary["timing"]["plant"]["loop_count"].as<int>() >= 1990);
  // The control loop's latency budget: each process timed its points of the loop, and the IMU
  // sample's age grows along the loop (the ages have one reference, the sample's due time).
  const std::vector<std::pair<std::string, std::string>> points = {{"plant", "plant: IMU sample published"},
                                                                   {"estimator", "estimator: IMU sample received"},
                                                                   {"estimator", "estimator: ESTIMATE published"},
                                                                   {"controller", "controller: ESTIMATE received"},
                                                                   {"controller", "controller: ACTUATOR_CMD published"},
                                                                   {"plant", "plant: ACTUATOR_CMD received"}};
  double previous_p50 = 0.0;
  for (const auto& [process, stage] : points) {
    INFO(stage);
    YAML::Node found;
    const YAML::Node stages = r.summary["timing"][process]["stages"];
    for (std::size_t i = 0; i < stages.size(); ++i) {
      if (stages[i]["stage"].as<std::string>() == stage) found.reset(stages[i]);
    }
    REQUIRE(found);
    CHECK(found["count"].as<int>() > 900);  // 2 s at 512 Hz
    CHECK(found["p50_us"].as<double>() >= previous_p50);
    CHECK(found["p99_us"].as<double>() >= found["p50_us"].as<double>());
    previous_p50 = found["p50_us"].as<double>();
  }
  // Each process's kernel channel filter is in place (it needs no privilege).
  for (const auto& f : r.summary["faults"]) {
    CHECK(f["message"].as<std::string>().find("channel filter") == std::string::npos);
  }
  // A real-time log carries the wall clock: its TRUTH spans the run as it happened.
  const std::vector<int64_t> t = nimble::test::event_times_us(dir + "/run.lcmlog", kTruth);
  REQUIRE(t.size() > 1900);
  CHECK(static_cast<double>(t.back() - t.front()) == Approx(2e6).margin(0.2e6));
}

TEST_CASE("real-time health: a run whose messages come late says so, and --strict-timing makes it an exit code",
          "[system]") {
  // A late threshold of 1 us makes every stream message late at every receiving process: a
  // degraded run made on purpose, the same on any machine.
  const std::string dir = scratch_dir("strict_timing");
  const RunResult r = rig_run(kConfigs + "hover.yaml", dir,
                              "--clock realtime --set duration_s=1 --set run.late_threshold_us=1 --strict-timing");
  INFO(r.output);
  CHECK(r.exit_code == 4);
  const YAML::Node h = r.summary["realtime_health"];
  REQUIRE(h);
  CHECK(h["degraded"].as<bool>());
  CHECK(h["worst_fraction"].as<double>() > 0.5);
  CHECK(r.summary["result"].as<std::string>().find("real-time degraded") == 0);
  CHECK(r.output.find("timing     real-time degraded") != std::string::npos);
  // Each process's own count of what reached it late is in the report.
  CHECK(r.summary["timing"]["plant"]["received"][kActuatorCommand]["late"].as<int>() > 100);
  // The run itself is whole: controlled, and the log has every TRUTH.
  CHECK(r.summary["controlled"].as<bool>());
  CHECK(channel_counts(dir + "/run.lcmlog").at(kTruth) >= 990);

  // The same run at the default threshold on this machine is judged, whatever the verdict.
  const std::string dir2 = scratch_dir("timing_default");
  const RunResult ok = rig_run(kConfigs + "hover.yaml", dir2, "--clock realtime --set duration_s=1");
  REQUIRE(ok.exit_code == 0);
  CHECK(ok.summary["realtime_health"]["text"].as<std::string>().find("real-time") == 0);
}

TEST_CASE("a process killed mid-run is named, the run fails, and the log stays readable", "[system]") {
  const std::string dir = scratch_dir("kill");
  const pid_t rig = rig_run_background(kConfigs + "hover.yaml", dir, "--clock realtime --set duration_s=8");
  const pid_t controller = wait_for_running(rig, "nimble_controller", dir + "/run.lcmlog");
  REQUIRE(controller > 0);
  ::kill(controller, SIGKILL);
  const int code = wait_exit_code(rig);
  const std::string out = slurp(dir + "/out.txt");
  INFO(out);
  CHECK(code == 3);
  CHECK(out.find("process 'controller'") != std::string::npos);
  CHECK(out.find("killed by signal 9") != std::string::npos);
  // Everything recorded so far reads back.
  const auto truth = truth_payloads(dir + "/run.lcmlog");
  CHECK(truth.size() > 10);
  CHECK(YAML::LoadFile(dir + "/summary.json")["exit_code"].as<int>() == 3);
}

TEST_CASE("a stalled lockstep participant is named with its channel, the run stops", "[system]") {
  const std::string dir = scratch_dir("stall");
  const pid_t rig = rig_run_background(kConfigs + "hover.yaml", dir,
                                       "--clock lockstep --set duration_s=600 --set lockstep.ack_timeout_ms=500");
  const pid_t controller = wait_for_running(rig, "nimble_controller", dir + "/run.lcmlog");
  REQUIRE(controller > 0);
  ::kill(controller, SIGSTOP);
  const int code = wait_exit_code(rig);
  ::kill(controller, SIGCONT);
  const std::string out = slurp(dir + "/out.txt");
  INFO(out);
  CHECK(code == 3);
  CHECK(out.find("no STEP_ACK from 'controller'") != std::string::npos);
  CHECK(out.find("process 'plant'") != std::string::npos);
}

TEST_CASE("command timeout: the plant holds the safe state and reports it", "[system]") {
  const std::string dir = scratch_dir("timeout");
  // The controller's own failsafe on a stale input is another test's: a machine loaded enough to
  // hold the controller off for 50 ms would engage it before the plant's timeout is seen.
  const pid_t rig = rig_run_background(kConfigs + "hover.yaml", dir,
                                       "--clock realtime --set duration_s=3 --set controller.failsafe.input_stale_s=2");
  const pid_t controller = wait_for_running(rig, "nimble_controller", dir + "/run.lcmlog");
  REQUIRE(controller > 0);
  ::kill(controller, SIGSTOP);
  std::this_thread::sleep_for(std::chrono::milliseconds(500));  // > command_timeout_s = 0.1 s
  ::kill(controller, SIGCONT);
  const int code = wait_exit_code(rig);
  const std::string out = slurp(dir + "/out.txt");
  INFO(out);
  CHECK(code == 0);
  bool timeout_fault = false, resumed = false, safe_feedback = false;
  const std::string log = dir + "/run.lcmlog";
  for (const auto& f : decode_channel<nimble::fault_event_t>(log, kFault)) {
    if (f.code == nimble::fault_event_t::CODE_COMMAND_TIMEOUT && f.process == "plant") {
      if (f.message.find("safe state") != std::string::npos && f.severity == nimble::fault_event_t::SEVERITY_ERROR) {
        timeout_fault = true;
      }
      if (f.message.find("resumed") != std::string::npos) resumed = true;
    }
  }
  for (const auto& fb : decode_channel<nimble::actuator_feedback_t>(log, kActuatorFeedback)) {
    safe_feedback = safe_feedback || fb.safe_state;
  }
  CHECK(timeout_fault);
  CHECK(resumed);
  CHECK(safe_feedback);
}

TEST_CASE("bad scenario values stop the run before anything starts, naming the key", "[system]") {
  const std::string dir = scratch_dir("bad");
  RunResult r = rig_run(kConfigs + "hover.yaml", dir, "--set plant.rate_hz=abc");
  CHECK(r.exit_code == 2);
  CHECK(r.output.find("plant.rate_hz") != std::string::npos);
  CHECK(r.output.find("'abc'") != std::string::npos);
  r = rig_run(kConfigs + "hover.yaml", dir, "--set controller.mixing.roll_cmd_to_delta_f_radps=-5");
  CHECK(r.exit_code == 2);
  CHECK(r.output.find("roll_cmd_to_delta_f_radps") != std::string::npos);
  r = rig_run(kConfigs + "hover.yaml", dir, "--clock sometimes");
  CHECK(r.exit_code == 2);
  CHECK(r.output.find("--clock") != std::string::npos);
  CHECK_FALSE(fs::exists(dir + "/run.lcmlog"));
}

TEST_CASE("a rig log flows into the identification: export to CSV, identify the set-1 derivatives", "[system]") {
  const std::string dir = scratch_dir("ident");
  // Ideal sensing: the log has no ESTIMATE, so the truth is the measured data.
  const RunResult r = rig_run(
      kConfigs + "id_doublet_train_fast.yaml", dir,
      "--clock lockstep --set run.controller_input=truth --set processes=[plant,controller] "
      "--set pilot.enabled=false");  // the pilot off: Eq 21 subtracts a constant w0 p, and with the pilot w moves from w0 to 0 (docs/paper-flights.md "Flights like the paper's")
  REQUIRE(r.exit_code == 0);
  const std::string log = dir + "/run.lcmlog", csv = dir + "/flight.csv", json = dir + "/ident.json";
  const auto exported = nimble::test::run_rig("export " + log + " --csv " + csv);
  INFO(exported.err);
  REQUIRE(exported.exit_code == 0);
  CHECK(exported.out.find("3071 samples at 512 Hz (states from truth)") != std::string::npos);
  // The CSV and the log itself identify the same model.
  for (const std::string& data : {csv, log}) {
    INFO(data);
    const auto ident = nimble::test::run_rig("identify " + data + " --w0 -0.30 --json " + json);
    INFO(ident.err);
    REQUIRE(ident.exit_code == 0);
    const YAML::Node p = YAML::LoadFile(json)["parameters"];
    // Set 1 (thesis Table 9.2), flown by the nonlinear plant, measured by its truth.
    const std::map<std::string, double> set1 = {{"Lp", -2.43e-4},  {"Lv", -3.74e-4}, {"L_df", 1.06e-4},
                                                {"L_dt", 4.19e-5}, {"Yv", -5.61e-2}, {"Y_df", -8.63e-4}};
    for (const auto& [name, truth] : set1) {
      INFO(name);
      CHECK(p[name]["value"].as<double>() == Approx(truth).epsilon(0.10));
    }
  }
  // Closed-loop validation: the set-1 model with the controller copy follows the flight;
  // a model with half the roll control derivative does not.
  const auto closed = nimble::test::run_rig("validate " + kConfigs + "models/nimble_lateral_set1.yaml " + log +
                                            " --closed-loop --json " + json);
  INFO(closed.err);
  REQUIRE(closed.exit_code == 0);
  const YAML::Node good = YAML::LoadFile(json)["closed_loop"];
  CHECK(good["phi"]["r2"].as<double>() > 0.95);
  CHECK(good["p"]["r2"].as<double>() > 0.95);
  CHECK(good["delta_f"]["r2"].as<double>() > 0.95);
  std::string half = nimble::test::slurp(kConfigs + "models/nimble_lateral_set1.yaml");
  half.replace(half.find("L_df: 1.06e-04"), 14, "L_df: 0.53e-04");
  half.replace(half.find("../vehicles/"), 12, kConfigs + "vehicles/");
  std::ofstream(dir + "/half.yaml") << half;
  const auto wrong = nimble::test::run_rig("validate " + dir + "/half.yaml " + log + " --closed-loop --json " + json);
  REQUIRE(wrong.exit_code == 0);
  CHECK(YAML::LoadFile(json)["closed_loop"]["phi"]["r2"].as<double>() < 0.7);
}

TEST_CASE("rig check says whether LCM multicast can run, and how", "[system]") {
  const auto r = nimble::test::run_rig("check");
  INFO(r.out << r.err);
  // This machine runs the rig (the tests above prove it), so check must agree.
  CHECK(r.exit_code == 0);
  CHECK(r.out.find("LCM multicast on this host's loopback") != std::string::npos);
  const bool host = r.out.find("): works") != std::string::npos;
  const bool ns = r.out.find("private network namespace with multicast loopback: works") != std::string::npos;
  CHECK((host || ns));
  if (!host) CHECK(r.out.find("ip route add 224.0.0.0/4 dev lo") != std::string::npos);
}

TEST_CASE("the plant's IMU stream: 512 Hz, seeded, noisy around the truth", "[system]") {
  const std::string dir = scratch_dir("imu");
  const RunResult r = rig_run(kConfigs + "hover.yaml", dir, "--clock lockstep --set duration_s=4");
  REQUIRE(r.exit_code == 0);
  CHECK(r.summary["channels"][kImu]["rate_hz"].as<double>() == Approx(512.0).epsilon(0.01));
  CHECK(r.summary["channels"][kImu]["drops"].as<int>() == 0);
  // Each IMU sample is taken from the truth of the plant step at its time stamp.
  const std::map<int64_t, nimble::truth_state_t> truth = truth_by_utime(dir + "/run.lcmlog");
  const auto imu = decode_channel<nimble::imu_sample_t>(dir + "/run.lcmlog", kImu);
  REQUIRE(imu.size() == 4 * 512 + 1);
  double sum_err = 0, sum_err2 = 0, sum_az = 0;
  for (const auto& s : imu) {
    REQUIRE(truth.count(s.utime) == 1);
    const double e = s.gyro_radps[0] - truth.at(s.utime).omega_body_radps[0];
    sum_err += e;
    sum_err2 += e * e;
    sum_az += s.accel_mps2[2];
  }
  const double n = static_cast<double>(imu.size());
  const double err_sd = std::sqrt(sum_err2 / n - (sum_err / n) * (sum_err / n));
  INFO("gyro x error sd " << err_sd << " rad/s, mean az " << sum_az / n);
  // White noise alone is 0.05 deg/s = 8.7e-4 rad/s; flapping vibration adds to it.
  CHECK(err_sd > 8.7e-4 * 0.9);
  CHECK(err_sd < 0.5);
  CHECK(sum_az / n == Approx(-9.81).margin(0.2));
}

TEST_CASE("the motion-capture emulator: 200 Hz poses at mid-exposure, 0.85 mm marker error, latency", "[system]") {
  const std::string dir = scratch_dir("mocap");
  const RunResult r = rig_run(kConfigs + "hover.yaml", dir,
                              "--clock lockstep --set duration_s=4 --set processes=[plant,controller,mocap] "
                              "--set run.controller_input=truth");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  const YAML::Node c = r.summary["channels"][kMocapPose];
  CHECK(c["rate_hz"].as<double>() == Approx(200.0).epsilon(0.02));
  CHECK(c["drops"].as<int>() == 0);
  CHECK(r.summary["channels"][kRigClock]["rate_hz"].as<double>() ==
        Approx(r.summary["channels"][kRigClock]["expected_hz"].as<double>()).epsilon(0.01));
  const std::map<int64_t, nimble::truth_state_t> truth = truth_by_utime(dir + "/run.lcmlog");
  const auto poses = decode_channel<nimble::mocap_pose_t>(dir + "/run.lcmlog", kMocapPose);
  REQUIRE(poses.size() > 700);
  double error_sum = 0;
  int valid = 0;
  for (std::size_t i = 0; i < poses.size(); ++i) {
    const auto& p = poses[i];
    if (i > 0) REQUIRE(p.frame_number == poses[i - 1].frame_number + 1);
    // Lockstep: out at the first 200 Hz tick at or after the configured 5 ms, and stamped with it.
    CHECK(p.latency_us >= 5000);
    CHECK(p.latency_us < 10000);
    CHECK((p.utime + p.latency_us) % 5000 == 0);
    if (!p.tracking_valid) continue;
    // Truth at mid-exposure, interpolated between the plant steps around it.
    const auto hi = truth.lower_bound(p.utime);
    REQUIRE(hi != truth.end());
    REQUIRE(hi != truth.begin());
    const auto lo = std::prev(hi);
    const double a = static_cast<double>(p.utime - lo->first) / static_cast<double>(hi->first - lo->first);
    double e2 = 0;
    for (int k = 0; k < 3; ++k) {
      const double x = (1 - a) * lo->second.position_ned_m[k] + a * hi->second.position_ned_m[k];
      e2 += std::pow(p.position_m[k] - x, 2);
    }
    error_sum += std::sqrt(e2);
    ++valid;
  }
  const double mean_error_mm = 1000.0 * error_sum / valid;
  INFO("mean 3-D position error " << mean_error_mm << " mm over " << valid << " frames");
  CHECK(mean_error_mm == Approx(0.85).epsilon(0.1));
}

TEST_CASE("flying on the estimator: IMU and motion capture fused, controlled, deterministic in lockstep", "[system]") {
  const std::string a = scratch_dir("est_a"), b = scratch_dir("est_b");
  // The shipped scenario as it is: it flies on the estimator.
  const std::string args = "--clock lockstep";
  const RunResult ra = rig_run(kConfigs + "id_doublet_train_fast.yaml", a, args);
  INFO(ra.output);
  REQUIRE(ra.exit_code == 0);
  CHECK(ra.summary["controlled"].as<bool>());
  CHECK(ra.summary["returned_to_hover"].as<bool>());
  const YAML::Node e = ra.summary["estimator"];
  REQUIRE(e);
  // The thesis's own fusion: phi error about 0.5 deg, velocity about 0.01 m/s.
  CHECK(e["phi_rms_deg"].as<double>() < 1.0);
  CHECK(e["v_rms_mps"].as<double>() < 0.05);
  CHECK(e["samples"].as<int>() > 3000);
  CHECK(e["poses_rejected"].as<int>() >= 0);
  CHECK(e["poses_missing"].as<int>() >= 0);
  // Nothing dropped for its time, every velocity window covered, every IMU sample used.
  for (const char* key : {"poses_too_old", "poses_too_new", "velocity_windows_uncovered", "imu_rejected", "imu_gaps"}) {
    INFO(key);
    CHECK(e[key].as<int>() == 0);
  }
  CHECK(ra.summary["channels"][kEstimate]["rate_hz"].as<double>() == Approx(512.0).epsilon(0.01));
  // The controller flew on estimates.
  {
    int estimate_inputs = 0;
    for (const auto& st : decode_channel<nimble::controller_status_t>(a + "/run.lcmlog", kControllerStatus)) {
      estimate_inputs += st.input_source == nimble::controller_status_t::INPUT_ESTIMATE;
    }
    CHECK(estimate_inputs == 3072);
  }
  // Same scenario and seed, four processes in the loop: the same truth, bit for bit.
  const RunResult rb = rig_run(kConfigs + "id_doublet_train_fast.yaml", b, args);
  REQUIRE(rb.exit_code == 0);
  const auto ta = truth_payloads(a + "/run.lcmlog"), tb = truth_payloads(b + "/run.lcmlog");
  CHECK(differing(ta, tb) == 0);
}

TEST_CASE(
    "the coupled doublet: pitch 20 deg nose down (forward flight) and a 6 Hz roll doublet with the "
    "longitudinal model, held",
    "[system]") {
  const std::string dir = scratch_dir("coupled");
  const RunResult r = rig_run(kConfigs + "coupled_doublet_6hz.yaml", dir, "--clock lockstep");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  CHECK(r.summary["controlled"].as<bool>());
  CHECK(r.summary["returned_to_hover"].as<bool>());
  // The pitch loop really flew the 20 deg set-point, and stayed within the verdict's 60 deg.
  const double theta_deg = r.summary["max_abs"]["theta"].as<double>() * 180.0 / M_PI;
  CHECK(theta_deg > 15.0);
  CHECK(theta_deg < 60.0);
  CHECK(r.summary["max_abs"]["phi"].as<double>() > 0.15);
  // Nose down and forward through the forward-flight hold (1.2 to 2.0 s of the manoeuvre).
  double theta_sum = 0.0, u_end = 0.0;
  int n = 0;
  for (const auto& t : decode_channel<nimble::truth_state_t>(dir + "/run.lcmlog", kTruth)) {
    const double time_s = 1e-6 * static_cast<double>(t.utime);
    if (time_s < 1.2 || time_s > 2.0) continue;
    theta_sum += t.euler_rad[1];
    u_end = t.velocity_body_mps[0];
    ++n;
  }
  REQUIRE(n > 700);
  const double theta_mean_deg = theta_sum / n * 180.0 / M_PI;
  INFO("forward-flight hold: mean theta " << theta_mean_deg << " deg, u at its end " << u_end << " m/s");
  CHECK(theta_mean_deg < -3.0);
  CHECK(u_end > 0.1);
}

TEST_CASE("the CAN link without a usable interface stops the run before anything starts, naming why", "[system]") {
  const std::string dir = scratch_dir("can_missing");
  // No interface may be created: on a kernel without CAN the kernel is named, on one with CAN
  // the missing interface is.
  const RunResult r = rig_run(kConfigs + "hover.yaml", dir,
                              "--clock lockstep --set actuator_link=can --set can_bridge.interface=nimblenone0 "
                              "--set can_bridge.create_virtual=false");
  INFO(r.output);
  CHECK(r.exit_code == 2);
  CHECK(r.output.find("actuator_link can: ") != std::string::npos);
  const bool no_can = r.output.find("this kernel has no CAN support") != std::string::npos;
  const bool missing = r.output.find("CAN interface 'nimblenone0' does not exist") != std::string::npos;
  CHECK((no_can || missing));
  if (no_can) CHECK(r.output.find("tools/canvm/canvm run") != std::string::npos);
  CHECK_FALSE(fs::exists(dir + "/run.lcmlog.scenario.yaml"));  // nothing was started

  // A bad section value is named as well.
  const RunResult bad =
      rig_run(kConfigs + "hover.yaml", dir, "--set actuator_link=can --set can_bridge.health_rate_hz=0");
  CHECK(bad.exit_code == 2);
  CHECK(bad.output.find("can_bridge.health_rate_hz") != std::string::npos);
}

TEST_CASE("expected rates: every process expects its inputs at the run's configured rates, not at fixed ones",
          "[system]") {
  // TRUTH at 500 Hz instead of 1000, the control cycle at 256 Hz instead of 512: the processes'
  // TIMING_HEALTH names the rates of this run for what they receive.
  const std::string dir = scratch_dir("expected_rates");
  const RunResult r = rig_run(kConfigs + "id_doublet_train_fast.yaml", dir,
                              "--clock inprocess --set duration_s=1 --set plant.truth_rate_hz=500 "
                              "--set controller.rate_hz=256");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  std::map<std::string, std::map<std::string, double>> expected;  // process -> channel -> Hz
  for (const auto& h : decode_channel<nimble::timing_health_t>(dir + "/run.lcmlog", kTimingHealth)) {
    for (int i = 0; i < h.num_channels; ++i) {
      expected[h.process][h.channel[static_cast<std::size_t>(i)]] = h.expected_hz[static_cast<std::size_t>(i)];
    }
  }
  CHECK(expected["mocap"][kTruth] == 500.0);
  CHECK(expected["plant"][kActuatorCommand] == 256.0);
  CHECK(expected["estimator"][kImu] == 512.0);
  CHECK(expected["estimator"][kMocapPose] == 200.0);
  // The resolved scenario the processes load carries them.
  const YAML::Node resolved = YAML::LoadFile(dir + "/run.lcmlog.scenario.yaml");
  CHECK(resolved["expected_rates_hz"][kTruth].as<double>() == 500.0);
  CHECK(resolved["expected_rates_hz"][kActuatorCommand].as<double>() == 256.0);
  // The summary names the configuration the run flew (scenario and the content of its files).
  const std::string digest = r.summary["config_digest"].as<std::string>();
  CHECK(digest.size() == 16);
  CHECK(digest.find_first_not_of("0123456789abcdef") == std::string::npos);
}
