// Nothing lost when the disk is full: `rig run` in every executor ends failed with the byte, the
// file and the system's reason, its processes stopped, the log whole up to its last event and
// readable by `rig export`; a run whose log will not fit is refused before it starts; every other
// writer of the rig (run summaries, exports, models, campaign results) names the failure and
// leaves no partial file. The small disk is a tmpfs in a private mount namespace where the
// machine allows, else a file size limit (tests/support/small_disk.h); each case says which.

#include <fcntl.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "lcmlog/lcm_log.h"
#include "launcher/inprocess.h"
#include "launcher/recorder.h"
#include "launcher/run_plan.h"
#include "tests/support/small_disk.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using Catch::Matchers::Contains;
using nimble::test::SmallDisk;

namespace {

constexpr int64_t kDiskBytes = 300 * 1000;  // the 300 kB disk

std::string scratch(const std::string& tag) { return nimble::test::scratch_dir("full_disk_" + tag); }

struct Ran {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr
};

/// Runs `command` (through sh, in RIG_SOURCE_DIR) writing on `disk`: under its file size limit
/// when it is no tmpfs. The output comes back through a pipe, which no size limit touches.
Ran run_on(const SmallDisk& disk, const std::string& command) {
  int p[2];
  REQUIRE(::pipe(p) == 0);
  const pid_t pid = ::fork();
  REQUIRE(pid >= 0);
  if (pid == 0) {
    ::dup2(p[1], STDOUT_FILENO);
    ::dup2(p[1], STDERR_FILENO);
    ::close(p[0]);
    ::close(p[1]);
    if (!disk.tmpfs()) {
      const std::string prefix = disk.command_prefix();  // prlimit --fsize=N:N
      const rlim_t n = std::stoull(prefix.substr(prefix.find('=') + 1));
      const rlimit l{n, n};
      ::setrlimit(RLIMIT_FSIZE, &l);
    }
    if (::chdir(RIG_SOURCE_DIR) != 0) ::_exit(126);
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(p[1]);
  Ran r;
  char buf[4096];
  ssize_t n;
  while ((n = ::read(p[0], buf, sizeof buf)) > 0) r.output.append(buf, static_cast<std::size_t>(n));
  ::close(p[0]);
  int status = 0;
  ::waitpid(pid, &status, 0);
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  return r;
}

std::string rig() { return RIG_BIN; }

/// Every event of the log, read strictly (damage throws); returns the count.
int64_t whole_events(const std::string& log) {
  nimble::lcmlog::LcmLogReader reader(log);
  nimble::lcmlog::LogEventRecord ev;
  int64_t n = 0;
  while (reader.next(&ev)) ++n;
  return n;
}

/// A run on the small disk that fills it: ends failed, named; the log whole; export reads it.
void full_disk_run(const std::string& clock, const std::string& duration) {
  const std::string outside = scratch("outside_" + clock);
  SmallDisk disk(scratch("disk_" + clock), kDiskBytes);
  WARN("small disk: " << disk.describe());
  const std::string log = disk.dir() + "/run.lcmlog";
  const std::string json = outside + "/summary.json";
  const Ran r = run_on(disk, rig() + " run rig_configs/hover.yaml --clock " + clock + " --set duration_s=" + duration +
                                 " --log " + log + " --json " + json + " --no-progress --no-space-check");
  INFO(r.output);
  CHECK(r.exit_code == 3);
  CHECK_THAT(r.output, Contains("result     failed: log write failed at byte ") &&
                           Contains(" of " + log + ": " + disk.error_text()));
  REQUIRE(fs::exists(json));
  const YAML::Node summary = YAML::LoadFile(json);
  CHECK_THAT(summary["result"].as<std::string>(), Contains("failed: log write failed"));
  const YAML::Node kept = summary["log_kept"];
  REQUIRE(kept.IsMap());
  const int64_t events = kept["events"].as<int64_t>();
  const int64_t bytes = kept["bytes"].as<int64_t>();
  const double sim_s = kept["sim_time_s"].as<double>();
  // What the summary says is kept is exactly what the file holds, whole.
  CHECK(events > 100);
  CHECK(bytes <= kDiskBytes);
  CHECK(static_cast<int64_t>(fs::file_size(log)) == bytes);
  CHECK(whole_events(log) == events);
  CHECK(sim_s > 0.0);
  CHECK(sim_s < std::stod(duration));
  CHECK_THAT(r.output, Contains(std::to_string(events) + " events"));
  // The flight's processes were stopped: each exited (in process: returned).
  for (const auto& p : summary["processes"]) {
    INFO(p.first.as<std::string>());
    CHECK(p.second["exit_code"].as<int>() >= 0);
  }
  // The kept part exports as any log does.
  const Ran ex = run_on(disk, rig() + " export " + log + " --format mcap --out " + outside + "/kept.mcap");
  INFO(ex.output);
  CHECK(ex.exit_code == 0);
  CHECK(fs::exists(outside + "/kept.mcap"));
  fs::remove_all(outside);
}

}  // namespace

TEST_CASE("a lockstep run on a full disk ends failed, naming the byte and the reason, its log whole", "[resource]") {
  std::signal(SIGXFSZ, SIG_IGN);
  full_disk_run("lockstep", "6");
}

TEST_CASE("an in-process run on a full disk ends failed, naming the byte and the reason, its log whole", "[resource]") {
  std::signal(SIGXFSZ, SIG_IGN);
  full_disk_run("inprocess", "6");
}

TEST_CASE("a real-time run on a full disk ends failed, naming the byte and the reason, its log whole", "[resource]") {
  std::signal(SIGXFSZ, SIG_IGN);
  full_disk_run("realtime", "4");
}

TEST_CASE("a run whose log will not fit on its disk is refused before it starts, naming both sizes", "[resource]") {
  SmallDisk disk(scratch("refuse"), kDiskBytes);
  WARN("small disk: " << disk.describe());
  if (!disk.tmpfs()) {
    FAIL(
        "this machine allows no tmpfs mount (not root?): the free-space check before a run cannot be tested here; "
        "CI runs it as root");
  }
  const std::string log = disk.dir() + "/run.lcmlog";
  const Ran r = run_on(
      disk, rig() + " run rig_configs/hover.yaml --clock lockstep --set duration_s=6 --log " + log + " --no-progress");
  INFO(r.output);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.output, Contains("refused: the log " + log + " is expected to take ") &&
                           Contains("for 6.0 s simulated") && Contains("but its filesystem has ") &&
                           Contains("--no-space-check"));
  CHECK_FALSE(fs::exists(log));
  // A short run fits and flies.
  const Ran ok = run_on(disk, rig() + " run rig_configs/hover.yaml --clock inprocess --set duration_s=0.2 --log " +
                                  log + " --no-progress");
  INFO(ok.output);
  CHECK(ok.exit_code == 0);
  CHECK(whole_events(log) > 0);
}

TEST_CASE("a log size limit (--log-max-bytes) refuses a run expected past it, and a flight reaching it ends there",
          "[resource]") {
  const std::string d = scratch("limit");
  const std::string log = d + "/run.lcmlog";
  SmallDisk none(scratch("limit_unused"), 1 << 30);  // for run_on only: the log is on the real disk
  const Ran refused = run_on(none, rig() + " run rig_configs/hover.yaml --clock inprocess --set duration_s=6 --log " +
                                       log + " --no-progress --log-max-bytes 100000");
  INFO(refused.output);
  CHECK(refused.exit_code == 2);
  CHECK_THAT(refused.output, Contains("over its limit --log-max-bytes 100000"));
  CHECK_FALSE(fs::exists(log));
  // Past the check (an expectation can be low): the flight ends at the limit.
  nimble::launcher::RunOptions o;
  o.scenario_file = std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml";
  o.overrides.push_back({"duration_s", "6"});
  const nimble::launcher::RunPlan plan = nimble::launcher::load_run_plan(o);
  nimble::launcher::InprocessOptions io;
  io.log_file = log;
  io.log_max_bytes = 100000;
  const nimble::launcher::RunReport report = nimble::launcher::fly_inprocess(plan, io);
  CHECK(report.verdict.exit_code == nimble::launcher::kRunFailed);
  CHECK_THAT(report.verdict.text, Contains("log write failed at byte ") && Contains("limit of 100000 bytes"));
  CHECK(report.log.bytes <= 100000);
  CHECK(static_cast<int64_t>(fs::file_size(log)) == report.log.bytes);
  CHECK(whole_events(log) == report.log.events);
  // The flight was ended early, not flown to its end.
  CHECK(report.sim_time_s < 5.0);
  fs::remove_all(d);
}

TEST_CASE("every other writer names a full disk and leaves no partial file", "[resource]") {
  std::signal(SIGXFSZ, SIG_IGN);
  const std::string outside = scratch("writers_src");
  const std::string log = outside + "/train.lcmlog";
  {
    SmallDisk big(scratch("writers_unused"), 1 << 30);
    const Ran made = run_on(
        big, rig() + " run rig_configs/id_doublet_train_fast.yaml --clock inprocess --log " + log + " --no-progress");
    INFO(made.output);
    REQUIRE(made.exit_code == 0);
  }
  SmallDisk disk(scratch("writers"), 64 * 1024);
  WARN("small disk: " << disk.describe());
  disk.fill_to(0);  // a tmpfs full; a size limit keeps each file under 64 kB
  struct Writer {
    std::string what, command, output;
  };
  const std::string d = disk.dir();
  const Writer writers[] = {
      {"rig export --format mcap", " export " + log + " --format mcap --compression none --out " + d + "/x.mcap",
       d + "/x.mcap"},
      {"rig export --csv", " export " + log + " --csv " + d + "/x.csv", d + "/x.csv"},
      {"rig identify --model-out", " identify " + log + " --model-out " + d + "/m.yaml", d + "/m.yaml"},
      {"rig identify --json", " identify " + log + " --json " + d + "/i.json", d + "/i.json"},
      {"rig run --json",
       " run rig_configs/hover.yaml --clock inprocess --set duration_s=1 --log " + outside +
           "/h.lcmlog --no-progress --json " + d + "/run.json",
       d + "/run.json"},
      {"rig run --mcap",
       " run rig_configs/hover.yaml --clock inprocess --set duration_s=1 --log " + outside +
           "/m.lcmlog --no-progress --mcap " + d + "/run.mcap",
       d + "/run.mcap"},
      {"rig sweep --csv",
       " sweep rig_configs/hover.yaml --seeds 1-3 --set duration_s=0.5 --no-progress --csv " + d + "/sweep.csv",
       d + "/sweep.csv"},
  };
  for (const Writer& w : writers) {
    const Ran r = run_on(disk, rig() + w.command);
    INFO(w.what << ": " << r.output);
    CHECK(r.exit_code != 0);
    CHECK_THAT(r.output, Contains(disk.error_text()));
    CHECK_THAT(r.output, Contains(w.output));
    // A run whose output after the flight failed says so in its result line, as its exit code does.
    if (w.what.rfind("rig run", 0) == 0) {
      CHECK(r.exit_code == 3);
      CHECK_THAT(r.output, Contains("result     failed: "));
      CHECK_THAT(r.output, !Contains("result     ok"));
    }
    // Nothing half written under the output's name, no temporary file left.
    CHECK_FALSE(fs::exists(w.output));
    for (const auto& e : fs::directory_iterator(d))
      CHECK(e.path().filename().string().find(".part") == std::string::npos);
  }
  fs::remove_all(outside);
}

TEST_CASE("the log size expected before a run is at most 15 % above what the flight writes, never below",
          "[resource]") {
  const std::string d = scratch("expected");
  for (const char* scenario : {"hover.yaml", "id_doublet_train_fast.yaml"}) {
    INFO(scenario);
    nimble::launcher::RunOptions o;
    o.scenario_file = std::string(RIG_SOURCE_DIR) + "/rig_configs/" + scenario;
    o.overrides.push_back({"duration_s", "4"});
    o.clock = "inprocess";
    const nimble::launcher::RunPlan plan = nimble::launcher::load_run_plan(o);
    nimble::launcher::InprocessOptions io;
    io.log_file = d + "/run.lcmlog";
    const nimble::launcher::RunReport report = nimble::launcher::fly_inprocess(plan, io);
    REQUIRE(report.log.failure.empty());
    const double written = static_cast<double>(fs::file_size(io.log_file));
    const double expected = static_cast<double>(nimble::launcher::expected_log_bytes(plan));
    CHECK(expected >= written);
    CHECK(expected <= 1.15 * written);
  }
  fs::remove_all(d);
}
