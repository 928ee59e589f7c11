// System tests of the in-process executor (`rig run --clock inprocess`) against the processes
// over LCM (`--clock lockstep`, in a private network namespace the launcher creates): the same
// scenario and seed give the same bytes on every data channel, the log reads the same, the CAN
// link through its codec changes nothing, and bad input is refused the same way.

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/truth_state_t.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"

#include "../support/rig_runs.h"

namespace ch = nimble::contract::channels;
using nimble::test::channel_payloads;
using nimble::test::differing;
using nimble::test::rig_run;
using nimble::test::RunResult;
using nimble::test::slurp;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

std::string scratch_dir(const std::string& tag) { return nimble::test::scratch_dir("inprocess_" + tag); }

/// The channels every processes' code publishes from simulated time only.
const std::vector<std::string> kDataChannels = {ch::kTruth,
                                                ch::kImu,
                                                ch::kMocapPose,
                                                ch::kEstimate,
                                                ch::kActuatorCommand,
                                                ch::kActuatorFeedback,
                                                ch::kAttitudeSetpoint,
                                                ch::kControllerStatus};

int run_command(const std::string& cmd) {
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace

TEST_CASE("in process and lockstep fly the same bytes on every data channel, with the estimator in the loop",
          "[system]") {
  const std::string a = scratch_dir("ls"), b = scratch_dir("ip");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  const std::string common = "--seed 5 --set duration_s=3";
  const RunResult lockstep = rig_run(scenario, a, "--clock lockstep " + common);
  const RunResult inprocess = rig_run(scenario, b, "--clock inprocess " + common);
  INFO(lockstep.output);
  INFO(inprocess.output);
  REQUIRE(lockstep.exit_code == 0);
  REQUIRE(inprocess.exit_code == 0);
  CHECK(inprocess.summary["clock"].as<std::string>() == "inprocess");
  CHECK(inprocess.summary["result"].as<std::string>() == "ok");
  for (const auto& channel : kDataChannels) {
    INFO(channel);
    const auto pa = channel_payloads(a + "/run.lcmlog", channel), pb = channel_payloads(b + "/run.lcmlog", channel);
    CHECK(pa.size() > 100);
    CHECK(differing(pa, pb) == 0);
  }
  CHECK(channel_payloads(b + "/run.lcmlog", ch::kTruth).size() == 3001);
  // The same report from either executor.
  for (const char* key : {"p", "v", "phi"}) {
    CHECK(inprocess.summary["max_abs"][key].as<double>() == lockstep.summary["max_abs"][key].as<double>());
  }
  CHECK(inprocess.summary["estimator"]["phi_rms_deg"].as<double>() ==
        lockstep.summary["estimator"]["phi_rms_deg"].as<double>());
  CHECK(inprocess.summary["channels"][ch::kRigClock]["count"].as<int>() > 0);
  CHECK(inprocess.summary["channels"][ch::kStepAck]["drops"].as<int>() == 0);
  // Not trivially equal: the vehicle flew the doublets, and another seed flies other noise.
  CHECK(inprocess.summary["max_abs"]["phi"].as<double>() > 0.3);
  const std::string c = scratch_dir("ip_seed6");
  REQUIRE(rig_run(scenario, c, "--clock inprocess --seed 6 --set duration_s=3").exit_code == 0);
  CHECK(differing(channel_payloads(b + "/run.lcmlog", ch::kImu), channel_payloads(c + "/run.lcmlog", ch::kImu)) > 0);

  // The log is the same format: `rig export` reads both into the same identification CSV.
  const std::string export_a = std::string(RIG_BIN) + " export " + a + "/run.lcmlog --csv " + a + "/run.csv";
  const std::string export_b = std::string(RIG_BIN) + " export " + b + "/run.lcmlog --csv " + b + "/run.csv";
  REQUIRE(run_command(export_a + " > /dev/null 2>&1") == 0);
  REQUIRE(run_command(export_b + " > /dev/null 2>&1") == 0);
  const std::string csv = slurp(b + "/run.csv");
  CHECK(csv.size() > 10000);
  CHECK(csv == slurp(a + "/run.csv"));
  // Both logs carry simulated time: the 3 s flight spans 3 s of event time, so lcm-logplayer
  // replays it at real speed, though it was flown in far less wall time.
  for (const std::string& log : {a + "/run.lcmlog", b + "/run.lcmlog"}) {
    INFO(log);
    const std::vector<int64_t> t = nimble::test::event_times_us(log, ch::kTruth);
    REQUIRE(t.size() == 3001);
    CHECK(std::is_sorted(t.begin(), t.end()));
    CHECK(t.back() - t.front() == Approx(3e6).margin(2000));
  }
  CHECK(inprocess.summary["wall_time_s"].as<double>() < 1.0);
  // And the resolved scenario lies next to it, as for every run.
  CHECK(std::filesystem::exists(b + "/run.lcmlog.scenario.yaml"));
}

TEST_CASE("in process over the CAN link: frames through the codec, the truth of lockstep over LCM", "[system]") {
  const std::string a = scratch_dir("lcm"), b = scratch_dir("can"), c = scratch_dir("canfd");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  const std::string common = "--seed 3 --set duration_s=2";
  const RunResult over_lcm = rig_run(scenario, a, "--clock lockstep " + common);
  const RunResult over_can = rig_run(scenario, b, "--clock inprocess --set actuator_link=can " + common);
  const RunResult over_fd =
      rig_run(scenario, c, "--clock inprocess --set actuator_link=can --set can_bridge.fd=true " + common);
  INFO(over_can.output);
  REQUIRE(over_lcm.exit_code == 0);
  REQUIRE(over_can.exit_code == 0);
  REQUIRE(over_fd.exit_code == 0);
  const auto truth = channel_payloads(a + "/run.lcmlog", ch::kTruth);
  CHECK(differing(truth, channel_payloads(b + "/run.lcmlog", ch::kTruth)) == 0);
  CHECK(differing(truth, channel_payloads(c + "/run.lcmlog", ch::kTruth)) == 0);
  // Every command crossed as frames and came back as the plant's input.
  const YAML::Node flight = over_can.summary["can"]["can_flight"], rig = over_can.summary["can"]["can_rig"];
  const int commands = over_can.summary["channels"][ch::kActuatorCommand]["count"].as<int>();
  CHECK(commands == 1024);
  CHECK(flight["messages_to_can"].as<int>() == commands);
  CHECK(rig["messages_to_lcm"].as<int>() == commands);
  CHECK(over_can.summary["channels"][ch::kActuatorCommandCan]["count"].as<int>() == commands);
  CHECK(flight["frames_sent"].as<int>() == rig["frames_received"].as<int>());
  CHECK(rig["rejected_bad_checksum"].as<int>() == 0);
  CHECK(rig["rejected_stale_counter"].as<int>() == 0);
  CHECK(over_fd.summary["can"]["can_rig"]["fd_frames_received"].as<int>() ==
        over_fd.summary["can"]["can_rig"]["frames_received"].as<int>());
}

TEST_CASE("in process: bad input is refused before the run, naming the key, and a wrong clock names the choices",
          "[system]") {
  const std::string d = scratch_dir("bad");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  const RunResult bad_rate = rig_run(scenario, d, "--clock inprocess --set plant.rate_hz=-5");
  CHECK(bad_rate.exit_code == 2);
  CHECK(bad_rate.output.find("plant.rate_hz") != std::string::npos);
  const RunResult bad_clock = rig_run(scenario, d, "--clock warp");
  CHECK(bad_clock.exit_code == 2);
  CHECK(bad_clock.output.find("--clock: warp not in {realtime,lockstep,inprocess}") != std::string::npos);
  const RunResult bad_process = rig_run(scenario, d, "--clock inprocess --set processes=[plant,autopilot]");
  CHECK(bad_process.exit_code == 2);
  CHECK(bad_process.output.find("autopilot") != std::string::npos);
}

TEST_CASE("bad input a new user gives is refused before the run, with a message that names it", "[system]") {
  const std::string d = scratch_dir("bad_input");
  const std::string scenario = kConfigs + "hover.yaml";
  // A key given twice: both lines named.
  const std::string dup = d + "/dup.yaml";
  {
    std::ifstream in(scenario);
    std::ofstream out(dup);
    std::string line;
    while (std::getline(in, line)) {
      out << line << "\n";
      if (line.rfind("seed:", 0) == 0) out << "duration_s: 3.0\n";
    }
  }
  // (the copy's relative paths resolve against its own folder: the same files are linked there)
  for (const char* sub :
       {"models", "manoeuvres", "plant", "controller", "sensing", "run", "vehicles", "turbulence", "pilot"}) {
    std::filesystem::create_directory_symlink(kConfigs + sub, d + "/" + sub);
  }
  const RunResult twice = rig_run(dup, d, "--clock inprocess");
  CHECK(twice.exit_code == 2);
  CHECK(twice.output.find("key 'duration_s': key given twice (lines 4 and 7)") != std::string::npos);
  // A bad value is named on the line it is written on, and a --set value on --set.
  const std::string bad_line = d + "/bad_line.yaml";
  {
    std::ifstream in(scenario);
    std::ofstream out(bad_line);
    std::string line;
    while (std::getline(in, line)) out << (line.rfind("duration_s:", 0) == 0 ? "duration_s: -3.0" : line) << "\n";
  }
  const RunResult on_line = rig_run(bad_line, d, "--clock inprocess");
  CHECK(on_line.exit_code == 2);
  CHECK(on_line.output.find("bad_line.yaml:4: key 'duration_s'") != std::string::npos);
  const RunResult on_set = rig_run(scenario, d, "--clock inprocess --set plant.rate_hz=-5");
  CHECK(on_set.exit_code == 2);
  CHECK(on_set.output.find("--set: key 'plant.rate_hz'") != std::string::npos);
  // A directory where the scenario should be.
  const RunResult directory = rig_run(kConfigs, d, "--clock inprocess");
  CHECK(directory.exit_code == 2);
  CHECK(directory.output.find("is a directory, not a file") != std::string::npos);
  // A negative seed is not read as 2^64 - 1.
  const RunResult negative = rig_run(scenario, d, "--clock inprocess --seed -1");
  CHECK(negative.exit_code == 2);
  CHECK(negative.output.find("--seed: '-1' is not a whole number >= 0") != std::string::npos);
  CHECK(negative.output.find("18446744073709551615") == std::string::npos);
  // A summary that could not be written is found before the flight, not after it.
  const RunResult unwritable = rig_run(scenario, d, "--clock inprocess --json /nonexistent-dir/summary.json");
  CHECK(unwritable.exit_code == 2);
  CHECK(unwritable.output.find("--json /nonexistent-dir/summary.json: cannot be written") != std::string::npos);
  CHECK(unwritable.output.find("run summary") == std::string::npos);  // nothing flew
}

TEST_CASE("every log reader refuses a damaged rig log naming the offset and the event, --salvage reads the rest",
          "[system]") {
  const std::string d = scratch_dir("damaged_log");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  REQUIRE(rig_run(scenario, d, "--clock inprocess --set duration_s=3").exit_code == 0);
  // The log cut a little after its middle, inside an event.
  const std::string whole = d + "/run.lcmlog", cut = d + "/cut.lcmlog";
  const auto size = std::filesystem::file_size(whole);
  std::filesystem::copy_file(whole, cut);
  std::filesystem::resize_file(cut, size / 2 + 7);
  const std::string model = kConfigs + "models/nimble_lateral_set1.yaml";
  const std::vector<std::string> readers = {
      "export " + cut + " --csv " + d + "/out.csv",
      "identify " + cut,
      "validate " + model + " " + cut,
      "discrepancy " + cut + " --model " + model,
  };
  for (const std::string& args : readers) {
    INFO(args);
    const std::string out = d + "/reader.txt";
    CHECK(run_command(std::string(RIG_BIN) + " " + args + " > " + out + " 2>&1") != 0);
    const std::string text = slurp(out);
    INFO(text);
    CHECK(text.find(cut) != std::string::npos);
    CHECK(text.find("damaged at byte ") != std::string::npos);
    CHECK(text.find("whole events") != std::string::npos);
  }
  // --salvage: the events before the damage, and a warning that says how much was left.
  const std::string out = d + "/salvage.txt";
  CHECK(run_command(std::string(RIG_BIN) + " export " + cut + " --csv " + d + "/part.csv --salvage > " + out +
                    " 2>&1") == 0);
  const std::string text = slurp(out);
  CHECK(text.find("warning: " + cut) != std::string::npos);
  CHECK(text.find("% of the file)") != std::string::npos);
  REQUIRE(run_command(std::string(RIG_BIN) + " export " + whole + " --csv " + d + "/full.csv > /dev/null 2>&1") == 0);
  const std::string part = slurp(d + "/part.csv"), full = slurp(d + "/full.csv");
  const auto part_rows = std::count(part.begin(), part.end(), '\n');
  const auto full_rows = std::count(full.begin(), full.end(), '\n');
  CHECK(part_rows < full_rows);
  CHECK(part_rows > full_rows / 3);
}
