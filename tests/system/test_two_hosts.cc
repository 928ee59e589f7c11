// System tests of a rig split over two hosts (the scenario's `hosts` section): the launcher
// emulates the second machine with a network namespace of its own, joined to its own by a veth
// pair, and flies on an LCM URL with ttl=1. The same scenario on one host and on two gives the
// same verdict, and in lockstep the same truth, byte for byte. These tests need network
// namespaces and veth: on a machine without them the runs fail (exit 2, naming why), and so
// do the tests.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/truth_state_t.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"

#include "../support/rig_runs.h"

namespace fs = std::filesystem;
namespace ch = nimble::contract::channels;
using nimble::test::channel_payloads;
using nimble::test::decode_channel;
using nimble::test::differing;
using nimble::test::rig_run;
using nimble::test::RunResult;
using nimble::test::slurp;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";
/// The shipped split: plant and mocap on "sim" (the launcher's host), controller and estimator on "flight".
const std::string kTwoHosts = kConfigs + "ol_doublet_6hz_two_hosts.yaml";
/// The same scenario on one host.
const std::string kOneHost = kConfigs + "ol_doublet_6hz_fast.yaml";

std::string scratch_dir(const std::string& tag) { return nimble::test::scratch_dir("hosts_" + tag); }

/// The network namespace of process `pid`, as the kernel names it ("net:[...]"), or "".
std::string namespace_of(pid_t pid) {
  std::error_code ec;
  const fs::path target = fs::read_symlink("/proc/" + std::to_string(pid) + "/ns/net", ec);
  return ec ? "" : target.string();
}

/// Processes that hold the network namespace `id` ("net:[...]") as their own or by an open
/// descriptor, as "pid (comm)".
std::vector<std::string> holders_of(const std::string& id) {
  std::vector<std::string> out;
  for (const auto& entry : fs::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::error_code ec;
    bool holds = fs::read_symlink(entry.path() / "ns" / "net", ec).string() == id;
    for (fs::directory_iterator fd(entry.path() / "fd", ec), end; !holds && !ec && fd != end; fd.increment(ec)) {
      std::error_code link_ec;
      holds = fs::read_symlink(fd->path(), link_ec).string() == id;
    }
    if (holds) out.push_back(pid + " (" + slurp((entry.path() / "comm").string()) + ")");
  }
  return out;
}

/// What every run over two hosts shows: each process on its host in the report, the hosts line
/// in the summary, the ttl=1 URL, and nothing left of the second host once the run is over.
void check_split_report(const RunResult& r) {
  const YAML::Node& s = r.summary;
  REQUIRE(s["hosts"]);
  CHECK(s["lcm_url"].as<std::string>().find("ttl=1") != std::string::npos);
  CHECK(s["processes"]["plant"]["host"].as<std::string>() == "sim");
  CHECK(s["processes"]["mocap"]["host"].as<std::string>() == "sim");
  CHECK(s["processes"]["controller"]["host"].as<std::string>() == "flight");
  CHECK(s["processes"]["estimator"]["host"].as<std::string>() == "flight");
  CHECK(s["hosts"]["sim"]["launcher"].as<bool>());
  CHECK_FALSE(s["hosts"]["flight"]["launcher"].as<bool>());
  CHECK(s["hosts"]["sim"]["address"].as<std::string>() == "10.76.67.1/30");
  CHECK(s["hosts"]["flight"]["address"].as<std::string>() == "10.76.67.2/30");
  const std::string sim_ns = s["hosts"]["sim"]["network_namespace"].as<std::string>();
  const std::string flight_ns = s["hosts"]["flight"]["network_namespace"].as<std::string>();
  CHECK(sim_ns.rfind("net:[", 0) == 0);
  CHECK(flight_ns.rfind("net:[", 0) == 0);
  CHECK(sim_ns != flight_ns);
  CHECK(r.output.find("hosts      sim (launcher, 10.76.67.1/30, " + sim_ns +
                      "): plant, mocap; flight (10.76.67.2/30, " + flight_ns + "): controller, estimator") !=
        std::string::npos);
  // The second host's namespace (and the veth pair with it) is gone: nothing holds it.
  CHECK(holders_of(flight_ns).empty());
}

}  // namespace

TEST_CASE("lockstep over two hosts: the verdict and the truth, byte for byte, of one host", "[system]") {
  const std::string a = scratch_dir("ls_one"), b = scratch_dir("ls_two");
  const std::string common = "--clock lockstep --seed 4 --set duration_s=3";
  const RunResult one = rig_run(kOneHost, a, common);
  const RunResult two = rig_run(kTwoHosts, b, common);
  INFO(one.output);
  INFO(two.output);
  REQUIRE(one.exit_code == 0);
  REQUIRE(two.exit_code == 0);
  CHECK(two.summary["result"].as<std::string>() == one.summary["result"].as<std::string>());
  CHECK(two.summary["controlled"].as<bool>() == one.summary["controlled"].as<bool>());
  CHECK(two.summary["returned_to_hover"].as<bool>() == one.summary["returned_to_hover"].as<bool>());
  CHECK_FALSE(one.summary["hosts"]);
  check_split_report(two);

  // The truth: every TRUTH message decoded from each log, the same, and the same bytes.
  const auto truth_one = decode_channel<nimble::truth_state_t>(a + "/run.lcmlog", ch::kTruth);
  const auto truth_two = decode_channel<nimble::truth_state_t>(b + "/run.lcmlog", ch::kTruth);
  REQUIRE(truth_one.size() == 3001);
  REQUIRE(truth_two.size() == truth_one.size());
  std::size_t different = 0;
  for (std::size_t i = 0; i < truth_one.size(); ++i) {
    const auto& x = truth_one[i];
    const auto& y = truth_two[i];
    bool same = x.utime == y.utime && x.seq == y.seq && x.step == y.step && x.delta_f_radps == y.delta_f_radps;
    for (int k = 0; k < 3; ++k) {
      same = same && x.omega_body_radps[k] == y.omega_body_radps[k] &&
             x.velocity_body_mps[k] == y.velocity_body_mps[k] && x.euler_rad[k] == y.euler_rad[k] &&
             x.position_ned_m[k] == y.position_ned_m[k];
    }
    different += !same;
  }
  CHECK(different == 0);
  CHECK(differing(channel_payloads(a + "/run.lcmlog", ch::kTruth), channel_payloads(b + "/run.lcmlog", ch::kTruth)) ==
        0);
  // Not trivially equal: the vehicle flew the doublet.
  CHECK(two.summary["max_abs"]["phi"].as<double>() > 0.1);

  // Every stream crossed the link where it had to, both ways, and stayed on its host where it
  // could (multicast loop): TRUTH and IMU sim -> flight, MOCAP_POSE sim -> flight, ESTIMATE on
  // flight, ACTUATOR_CMD flight -> sim, STEP_ACK both ways; all at their rates, nothing dropped.
  for (const std::string& channel : {ch::kTruth, ch::kImu, ch::kMocapPose, ch::kEstimate, ch::kActuatorCommand,
                                     ch::kActuatorFeedback, ch::kRigClock, ch::kStepAck}) {
    INFO(channel);
    const YAML::Node c = two.summary["channels"][channel];
    REQUIRE(c);
    CHECK(c["count"].as<long long>() == one.summary["channels"][channel]["count"].as<long long>());
    CHECK(c["drops"].as<int>() == 0);
    CHECK(c["malformed"].as<int>() == 0);
  }
  // The controller flew on estimates that crossed nothing, from poses and IMU samples that crossed.
  CHECK(two.summary["estimator"]["samples"].as<int>() > 1500);
  CHECK(two.summary["estimator"]["phi_rms_deg"].as<double>() == one.summary["estimator"]["phi_rms_deg"].as<double>());
}

TEST_CASE("real time over two hosts: controlled as on one host, each process in its host's namespace", "[system]") {
  const std::string a = scratch_dir("rt_one"), b = scratch_dir("rt_two");
  const std::string common = "--clock realtime --set duration_s=2";
  const RunResult one = rig_run(kOneHost, a, common);
  INFO(one.output);
  REQUIRE(one.exit_code == 0);

  // The split run in the background, to see where its processes live while it flies.
  const pid_t rig = nimble::test::rig_run_background(kTwoHosts, b, common);
  const pid_t controller = nimble::test::wait_for_running(rig, "nimble_controller", b + "/run.lcmlog");
  const pid_t plant = nimble::test::child_named(rig, "nimble_plant");
  const pid_t mocap = nimble::test::child_named(rig, "nimble_mocap");
  const pid_t estimator = nimble::test::child_named(rig, "nimble_estimator");
  const std::string rig_ns = namespace_of(rig), controller_ns = namespace_of(controller),
                    plant_ns = namespace_of(plant), mocap_ns = namespace_of(mocap),
                    estimator_ns = namespace_of(estimator);
  const int code = nimble::test::wait_exit_code(rig);
  const std::string out = slurp(b + "/out.txt");
  INFO(out);
  REQUIRE(controller > 0);
  REQUIRE(code == 0);
  CHECK_FALSE(rig_ns.empty());
  CHECK_FALSE(controller_ns.empty());
  CHECK(plant_ns == rig_ns);
  CHECK(mocap_ns == rig_ns);
  CHECK(controller_ns != rig_ns);
  CHECK(estimator_ns == controller_ns);
  CHECK(rig_ns != namespace_of(::getpid()));  // the launcher's host is a private namespace too

  const YAML::Node two = YAML::LoadFile(b + "/summary.json");
  CHECK(two["controlled"].as<bool>() == one.summary["controlled"].as<bool>());
  CHECK(two["returned_to_hover"].as<bool>() == one.summary["returned_to_hover"].as<bool>());
  CHECK(two["controlled"].as<bool>());
  CHECK(two["hosts"]["flight"]["network_namespace"].as<std::string>() == controller_ns);
  CHECK(two["hosts"]["sim"]["network_namespace"].as<std::string>() == rig_ns);
  check_split_report(RunResult{code, out, two});
  // The control loop closed across the link: commands from the flight computer, estimates on it,
  // none lost. (Near their rates: how near is the machine's real-time health, which the run
  // judges itself, and a test run in parallel with others may be degraded.)
  for (const std::string& channel : {ch::kTruth, ch::kActuatorCommand, ch::kEstimate}) {
    INFO(channel);
    const YAML::Node c = two["channels"][channel];
    CHECK(c["rate_hz"].as<double>() > 0.8 * c["expected_hz"].as<double>());
    CHECK(c["drops"].as<int>() == 0);
  }
  CHECK(two["timing"]["plant"]["latency_count"].as<int>() > 500);
}

/// Flies the 6 Hz doublet with host 'flight' (controller, estimator) started by hand, in a
/// private network namespace whose loopback carries multicast: the lab network of the test. The
/// commands `rig run` prints for that host are run as printed, as on the flight computer; with
/// `other_seed` the controller's command is given a copy of the resolved scenario with another
/// seed. Writes into `dir` (out.txt, summary.json, commands.txt); returns the script's exit code.
int fly_by_hand(const std::string& dir, const std::string& args, bool other_seed) {
  const std::string script = dir + "/lab.sh";
  const std::string resolved = dir + "/run.lcmlog.scenario.yaml";
  std::ofstream(script)
      << "set -u\n"
      << "ip link set lo up && ip route add 224.0.0.0/4 dev lo || exit 90\n"
      << RIG_BIN << " run " << kOneHost << " " << args
      << " --set run.network_namespace=never --set 'run.lcm_url=udpm://239.255.76.67:7667?ttl=1'"
      << " --set 'hosts={sim: [plant, mocap], flight: {processes: [controller, estimator], start: by_hand}}'"
      << " --log " << dir << "/run.lcmlog --json " << dir << "/summary.json --no-progress > " << dir
      << "/out.txt 2>&1 &\n"
      << "rig=$!\n"
      << "for i in $(seq 800); do [ \"$(grep -c -- '--lcm-url' " << dir
      << "/out.txt)\" = 2 ] && break; sleep 0.025; done\n"
      << "grep -- '--lcm-url' " << dir << "/out.txt > " << dir << "/commands.txt\n"
      << (other_seed ? "sed 's/^seed: .*/seed: 99/' " + resolved + " > " + dir + "/other.yaml\n" +
                           "sed -i '/--name controller/s#--scenario [^ ]*#--scenario " + dir + "/other.yaml#' " + dir +
                           "/commands.txt\n"
                     : std::string())
      << "while read -r command; do eval \"$command\" >> " << dir << "/by_hand.out 2>&1 & done < " << dir
      << "/commands.txt\n"
      << "wait $rig\n"
      << "code=$?\n"
      // The processes started by hand end on the run's stop command; whatever has not after a
      // moment is stopped here, so that a failed run leaves nothing behind.
      << "for i in $(seq 40); do [ -z \"$(jobs -pr)\" ] && break; sleep 0.05; done\n"
      << "kill $(jobs -pr) 2>/dev/null\n"
      << "exit $code\n";
  const int status = std::system(("unshare -n bash " + script).c_str());
  const int code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  if (code == 90)
    FAIL("this machine cannot give a private network namespace a multicast loopback (unshare -n, ip route)");
  return code;
}

TEST_CASE("a host started by hand: rig run prints its commands, they fly with it, the truth of one host", "[system]") {
  const std::string a = scratch_dir("hand_one"), b = scratch_dir("hand_two");
  const std::string common = "--clock lockstep --seed 4 --set duration_s=2";
  const RunResult one = rig_run(kOneHost, a, common);
  INFO(one.output);
  REQUIRE(one.exit_code == 0);
  const int code = fly_by_hand(b, common, false);
  const std::string out = slurp(b + "/out.txt");
  INFO(out);
  INFO("by hand: " << slurp(b + "/by_hand.out"));
  REQUIRE(code == 0);
  const std::string commands = slurp(b + "/commands.txt");
  CHECK(commands.find("nimble_controller --name controller --scenario " + b + "/run.lcmlog.scenario.yaml") !=
        std::string::npos);
  CHECK(commands.find("nimble_estimator --name estimator") != std::string::npos);
  const YAML::Node two = YAML::LoadFile(b + "/summary.json");
  CHECK(two["result"].as<std::string>() == one.summary["result"].as<std::string>());
  CHECK(two["processes"]["controller"]["host"].as<std::string>() == "flight");
  CHECK(two["processes"]["plant"]["host"].as<std::string>() == "sim");
  // Not the launcher's children: run.external_processes, known by their heartbeats.
  CHECK(out.find("controller(external, stopped, ") != std::string::npos);
  CHECK(out.find("estimator(external, stopped, ") != std::string::npos);
  const auto truth_one = channel_payloads(a + "/run.lcmlog", ch::kTruth);
  REQUIRE(truth_one.size() == 2001);
  CHECK(differing(truth_one, channel_payloads(b + "/run.lcmlog", ch::kTruth)) == 0);
  CHECK(two["channels"][ch::kActuatorCommand]["count"].as<int>() == 1024);
}

TEST_CASE("a process started by hand with another scenario is named before the run starts", "[system]") {
  const std::string d = scratch_dir("hand_other");
  const int code = fly_by_hand(d, "--clock lockstep --set duration_s=2", true);
  const std::string out = slurp(d + "/out.txt");
  INFO(out);
  CHECK(slurp(d + "/commands.txt").find("--scenario " + d + "/other.yaml") != std::string::npos);
  CHECK(code == 2);
  CHECK(out.find("process 'controller' (pid ") != std::string::npos);
  CHECK(out.find(") was started with another scenario: configuration digest ") != std::string::npos);
  CHECK(out.find("Start it with --scenario " + d + "/run.lcmlog.scenario.yaml") != std::string::npos);
  CHECK(out.find("process 'estimator'") == std::string::npos);  // the one given the run's scenario is not named
  CHECK(nimble::test::channel_counts(d + "/run.lcmlog").count(ch::kTruth) == 0);  // nothing flew
}

TEST_CASE("a bad hosts section stops the run before anything starts, naming the file, the line and why", "[system]") {
  const std::string d = scratch_dir("bad");
  const std::string file = d + "/split.yaml";
  std::ofstream(file) << "base: " << kOneHost << "\n"
                      << "hosts:\n"
                      << "  sim: [plant, mocap]\n"
                      << "  flight:\n"
                      << "    processes: [controller, estimator]\n"
                      << "    adress: 10.76.67.2/30\n";
  const RunResult typo = rig_run(file, d, "--clock lockstep");
  CHECK(typo.exit_code == 2);
  CHECK(typo.output.find("split.yaml:6: key 'hosts.flight.adress'") != std::string::npos);
  CHECK(typo.output.find("unknown key") != std::string::npos);
  CHECK_FALSE(fs::exists(d + "/run.lcmlog.scenario.yaml"));  // nothing was started

  // Given on the command line: named as --set, with the process and the hosts.
  const RunResult twice =
      rig_run(kOneHost, d, "--clock lockstep --set 'hosts={sim: [plant, controller], flight: [controller]}'");
  CHECK(twice.exit_code == 2);
  CHECK(twice.output.find("--set: key 'hosts.flight'") != std::string::npos);
  CHECK(twice.output.find("process 'controller' is placed twice (on hosts 'sim' and 'flight')") != std::string::npos);
  const RunResult unknown = rig_run(kOneHost, d, "--clock lockstep --set 'hosts={sim: [plant], flight: [autopilot]}'");
  CHECK(unknown.exit_code == 2);
  CHECK(unknown.output.find("process 'autopilot' is not one of the run's processes") != std::string::npos);
  // A CAN bridge side away from the host of the virtual CAN interface: refused, saying why.
  const RunResult can = rig_run(kOneHost, d,
                                "--clock lockstep --set actuator_link=can "
                                "--set 'hosts={sim: [plant], flight: [controller, can_flight]}'");
  CHECK(can.exit_code == 2);
  CHECK(can.output.find("the CAN bridge side 'can_flight' must run on the launcher's host 'sim'") != std::string::npos);
  CHECK(can.output.find("a vcan cannot span two hosts") != std::string::npos);
}
