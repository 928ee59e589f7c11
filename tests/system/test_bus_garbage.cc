// Fault tests (label `fault`): garbage on the bus of a real-time run. A process joins the run's
// network namespace (nsenter) and publishes random payloads on the rig's channels through
// liblcm, half of them behind the channel's real fingerprint, some with the zero-length
// string that makes LCM 1.3.1's decoders throw. Every process survives, the log stays
// readable, the malformed messages are counted, and the summary's figures are the real flight's.

#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"

#include "../support/rig_runs.h"

namespace ch = nimble::contract::channels;
using nimble::test::channel_counts;
using nimble::test::rig_run_background;
using nimble::test::slurp;
using nimble::test::wait_exit_code;
using nimble::test::wait_for_running;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

/// Floods the run of `rig run` (pid `rig`) from inside its network namespace.
int flood(pid_t rig, const std::string& args) {
  const std::string cmd = "nsenter -t " + std::to_string(rig) + " -n " + std::string(BUS_FLOOD_BIN) +
                          " --url 'udpm://239.255.76.67:7667?ttl=0' " + args + " > /dev/null 2>&1";
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

/// Flies hover in real time for `duration_s` while bus_flood runs with `flood_args`; checks
/// what every flood must leave intact and returns the summary. `lossless`: the real messages all
/// reached the launcher (a steady flood); otherwise a burst may overrun the receive buffers, and
/// what was lost must be counted as dropped, not made up.
YAML::Node fly_through(const std::string& tag, const std::string& flood_args, double duration_s, bool lossless) {
  const std::string dir = nimble::test::scratch_dir("garbage_" + tag);
  const pid_t rig = rig_run_background(kConfigs + "hover.yaml", dir,
                                       "--clock realtime --set duration_s=" + std::to_string(duration_s));
  REQUIRE(wait_for_running(rig, "nimble_plant", dir + "/run.lcmlog") > 0);
  CHECK(flood(rig, flood_args) == 0);
  const int code = wait_exit_code(rig);
  const std::string out = slurp(dir + "/out.txt");
  INFO(out);
  // Every process survived and the vehicle flew as without the garbage.
  CHECK(code == 0);
  const YAML::Node s = YAML::LoadFile(dir + "/summary.json");
  for (const auto& p : s["processes"]) {
    INFO(p.first.as<std::string>());
    CHECK(p.second["exit_code"].as<int>() == 0);
    CHECK(p.second["signal"].as<int>() == 0);
  }
  CHECK(s["controlled"].as<bool>());
  // The figures are those of the real messages: hover stays within a few degrees, the rates
  // are the rig's, nothing counted as dropped.
  CHECK(s["max_abs"]["phi"].as<double>() < 0.2);
  // Every TRUTH the plant published, received or counted as dropped: one per millisecond of the
  // run's simulated time. A real-time run ends on the wall clock, and under the flood its
  // simulated time may end a few milliseconds short of the duration (3.979 of 4 s seen on a
  // loaded machine): no message is lost by that.
  const YAML::Node truth = s["channels"][ch::kTruth];
  const double received = truth["count"].as<double>(), dropped = truth["drops"].as<double>();
  const double sim_time_s = s["sim_time_s"].as<double>();
  CHECK(sim_time_s >= 0.98 * duration_s);
  CHECK(received + dropped == Approx(1000.0 * sim_time_s).margin(5));
  if (lossless) {
    CHECK(dropped == 0);
    CHECK(s["channels"][ch::kActuatorCommand]["drops"].as<int>() == 0);
  }
  // The log reads to its end, with the real TRUTH it received in it (and the garbage, as recorded).
  const auto counts = channel_counts(dir + "/run.lcmlog");
  CHECK(counts.at(ch::kTruth) >= static_cast<int>(received));
  return s;
}

/// Malformed messages over every channel of a run summary.
int64_t malformed_total(const YAML::Node& summary) {
  int64_t n = 0;
  for (const auto& c : summary["channels"]) n += c.second["malformed"].as<int64_t>();
  return n;
}

}  // namespace

TEST_CASE(
    "garbage at 2000 messages per second: every process survives, the garbage is counted, the figures are "
    "the flight's",
    "[fault]") {
  const YAML::Node s = fly_through("steady", "--rate 2000 --seconds 2 --seed 3", 4.0, true);
  // About 4000 messages went out; the launcher hears all of them and trusts none.
  CHECK(malformed_total(s) > 3000);
  CHECK(s["channels"][ch::kTruth]["malformed"].as<int>() > 100);
  // The processes reported what reached them (their kernel filters let in only their channels).
  bool reported = false;
  for (const auto& f : s["faults"]) {
    reported |= f["code"].as<int>() == 2;  // CODE_MESSAGE_MALFORMED
  }
  CHECK(reported);
}

TEST_CASE(
    "garbage in bursts of 20000 messages: every process survives, and what the bursts pushed out is counted "
    "as dropped",
    "[fault]") {
  const YAML::Node s = fly_through("burst", "--burst 20000 --seconds 2 --seed 4", 4.0, false);
  CHECK(malformed_total(s) > 1000);
}
