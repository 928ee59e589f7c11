// One writer per output: a second `rig run` on a log that a run is writing is refused at once
// (exit 2, naming the log and the holder's pid) in every clock, and the first run's log reads back
// whole; the same for an MCAP file, from `rig run --mcap` and `rig export`; a writer killed while it
// held its output does not block the next one (the lock dies with it, no lock file goes stale).
//
// The first run is stopped (SIGSTOP) once it holds its log, so the second one meets it holding
// the lock whatever the machine's speed, then let go on (SIGCONT) to finish its flight.

#include <signal.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <filesystem>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "core/output_lock.h"
#include "tests/support/lock_wait.h"
#include "tests/support/rig_runs.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using nimble::test::holder_of;
using nimble::test::RigResult;
using nimble::test::run_rig;
using nimble::test::wait_for_holder;
using nimble::test::wait_for_no_holder;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

/// The events of every channel in the log, summed.
int events_in(const std::string& log) {
  int n = 0;
  for (const auto& [channel, count] : nimble::test::channel_counts(log)) n += count;
  return n;
}

}  // namespace

TEST_CASE(
    "one writer per log: a second run on a log being written is refused at once in every clock, the "
    "first run's log whole",
    "[resource]") {
  for (const std::string clock : {"inprocess", "lockstep", "realtime"}) {
    INFO("clock " << clock);
    const std::string a = nimble::test::scratch_dir("one_writer_log_" + clock);
    const std::string log = a + "/run.lcmlog";
    const pid_t first = nimble::test::rig_run_background(kConfigs + "hover.yaml", a,
                                                         "--clock " + clock + " --set duration_s=2 --seed 3");
    const int holder = wait_for_holder(log);
    ::kill(first, SIGSTOP);
    REQUIRE(holder > 0);
    // The second run: another seed, another summary, the same log.
    const RigResult second =
        run_rig("run " + kConfigs + "hover.yaml --clock " + clock +
                " --set duration_s=2 --seed 4 --no-progress --json " + a + "/second.json --log " + log);
    ::kill(first, SIGCONT);
    INFO(second.out << second.err);
    CHECK(second.exit_code == 2);
    CHECK_THAT(second.err, Contains("refused: the log " + log + " is being written by another process (pid " +
                                    std::to_string(holder)));
    CHECK_THAT(second.err, Contains("one writer per file"));
    CHECK_FALSE(fs::exists(a + "/second.json"));
    // The first run flew whole, and its log holds every event its summary counted.
    CHECK(nimble::test::wait_exit_code(first) == 0);
    const YAML::Node summary = YAML::LoadFile(a + "/summary.json");
    // Held stopped while the second was refused, a real-time run may come out late beyond its limit
    // (real-time degraded, exit code 0): the verdict on its timing, not on its log.
    const std::string result = summary["result"].as<std::string>();
    INFO("result: " << result);
    CHECK((result == "ok" || (clock == "realtime" && result.rfind("real-time degraded", 0) == 0)));
    int counted = 0;
    for (const auto& c : summary["channels"]) counted += c.second["count"].as<int>();
    CHECK(events_in(log) == summary["log_kept"]["events"].as<int>());
    CHECK(counted > 0);
    CHECK(holder_of(log) == -1);  // released with its holder
  }
}

TEST_CASE(
    "one writer per MCAP file: rig run --mcap and rig export on a file being written are refused, the "
    "first one's file whole",
    "[resource]") {
  const std::string a = nimble::test::scratch_dir("one_writer_mcap");
  const std::string mcap = a + "/run.mcap";
  // A whole log for the export to read.
  const RigResult source =
      run_rig("run " + kConfigs + "hover.yaml --clock inprocess --set duration_s=1 --no-progress --log " + a +
              "/source.lcmlog");
  REQUIRE(source.exit_code == 0);
  const pid_t first = nimble::test::rig_run_background(kConfigs + "hover.yaml", a,
                                                       "--clock lockstep --set duration_s=2 --mcap " + mcap);
  const int holder = wait_for_holder(mcap + ".part");
  ::kill(first, SIGSTOP);
  REQUIRE(holder > 0);
  const RigResult run =
      run_rig("run " + kConfigs + "hover.yaml --clock lockstep --set duration_s=2 --no-progress --log " + a +
              "/other.lcmlog --mcap " + mcap);
  const RigResult export_ = run_rig("export " + a + "/source.lcmlog --format mcap --out " + mcap);
  ::kill(first, SIGCONT);
  INFO(run.out << run.err << export_.out << export_.err);
  CHECK(run.exit_code == 2);
  CHECK_THAT(run.err, Contains("refused: --mcap: the MCAP file " + mcap +
                               ".part is being written by another process (pid " + std::to_string(holder)));
  CHECK_FALSE(fs::exists(a + "/other.lcmlog"));  // refused before the flight
  CHECK(export_.exit_code == 2);
  CHECK_THAT(export_.err,
             Contains("the MCAP file " + mcap + " is being written by another process (pid " + std::to_string(holder)));
  CHECK(nimble::test::wait_exit_code(first) == 0);
  // The first run's export is whole: renamed from its part, readable from its magic to its end.
  CHECK_FALSE(fs::exists(mcap + ".part"));
  REQUIRE(fs::exists(mcap));
  const std::string bytes = nimble::test::slurp(mcap);
  CHECK(bytes.substr(0, 5) == "\x89MCAP");
  CHECK(bytes.substr(bytes.size() - 8, 5) == "\x89MCAP");
}

TEST_CASE("one writer per log: a writer killed while it held the log does not block the next run", "[resource]") {
  const std::string a = nimble::test::scratch_dir("one_writer_killed");
  const std::string log = a + "/run.lcmlog";
  const pid_t first =
      nimble::test::rig_run_background(kConfigs + "hover.yaml", a, "--clock lockstep --set duration_s=4");
  REQUIRE(wait_for_holder(log) > 0);
  ::kill(first, SIGKILL);
  nimble::test::wait_exit_code(first);
  // Its processes end when their launcher dies (each on its parent-death signal, a few ms later
  // on a loaded machine), and the lock goes with the last of them: no lock file is left to clean.
  CHECK(wait_for_no_holder(log));
  const RigResult next =
      run_rig("run " + kConfigs + "hover.yaml --clock inprocess --set duration_s=1 --no-progress --log " + log +
              " --json " + a + "/next.json");
  INFO(next.out << next.err);
  CHECK(next.exit_code == 0);
  CHECK(events_in(log) == YAML::LoadFile(a + "/next.json")["log_kept"]["events"].as<int>());
}
