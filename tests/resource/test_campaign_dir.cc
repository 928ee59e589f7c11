// One writer per campaign directory, and a directory that is not the campaign's refused untouched
// (campaign/result_files.h): two `rig sweep --dir D` racing on one directory, 20 times, leave one
// campaign whose results are all its own; a user's directory, a stray result file and a result
// copied from another campaign are refused, naming what differs, by rig sweep, rig reproduce
// thesis --dir and rig discrepancy --power --dir alike; a holder that is killed blocks nothing.

#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include "core/output_lock.h"
#include "tests/support/campaign_files.h"
#include "tests/support/run_rig.h"
#include "tests/support/scratch.h"

extern char** environ;

namespace {

namespace fs = std::filesystem;
using nimble::test::run_rig;
using nimble::test::slurp;

const std::string kSource = std::string(RIG_SOURCE_DIR) + "/";
/// A tiny campaign: three hovers of 0.2 s in process, one at a time.
const std::string kSweep = "sweep " + kSource + "rig_configs/hover.yaml --set duration_s=0.2 --jobs 1 --no-progress";

/// `rig ARGS` started now, its stdout and stderr into `out`; returns its pid.
pid_t start_rig(const std::vector<std::string>& args, const std::string& out) {
  std::vector<std::string> argv = {RIG_BIN};
  argv.insert(argv.end(), args.begin(), args.end());
  std::vector<char*> p;
  for (auto& a : argv) p.push_back(a.data());
  p.push_back(nullptr);
  posix_spawn_file_actions_t actions;
  posix_spawn_file_actions_init(&actions);
  posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, out.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
  pid_t pid = -1;
  const int e = posix_spawn(&pid, RIG_BIN, &actions, nullptr, p.data(), environ);
  posix_spawn_file_actions_destroy(&actions);
  REQUIRE(e == 0);
  return pid;
}

int exit_code(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
  }
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

std::vector<std::string> sweep_args(const std::string& seeds, const std::string& dir) {
  return {"sweep",
          kSource + "rig_configs/hover.yaml",
          "--set",
          "duration_s=0.2",
          "--jobs",
          "1",
          "--no-progress",
          "--seeds",
          seeds,
          "--dir",
          dir};
}

/// The seeds of DIR/result.json's runs, and that each run is whole (its verdict and exit code there).
std::multiset<int> result_seeds(const std::string& dir) {
  const nlohmann::json j = nlohmann::json::parse(slurp(dir + "/result.json"));
  std::multiset<int> seeds;
  for (const auto& run : j.at("runs")) {
    CHECK(run.at("exit_code").get<int>() == 0);
    seeds.insert(run.at("seed").get<int>());
  }
  return seeds;
}

std::size_t files_in(const std::string& dir) {
  std::size_t n = 0;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) n += e.is_regular_file();
  return n;
}

}  // namespace

TEST_CASE(
    "campaign directory: two rig sweep --dir racing on one directory, 20 times: one writer, the campaign left "
    "holds its own results whole",
    "[resource]") {
  const std::string d = nimble::test::scratch_dir("campaign_race");
  int busy = 0, other = 0, resumed = 0, intact = 0;
  for (int k = 0; k < 20; ++k) {
    const std::string dir = d + "/c" + std::to_string(k);
    // Even races: two campaigns (seeds 1-3 and 101-103); odd ones: the same campaign twice.
    const bool same = k % 2 == 1;
    const std::string seeds[2] = {"1-3", same ? "1-3" : "101-103"};
    const std::string out[2] = {dir + ".a.txt", dir + ".b.txt"};
    const pid_t pid[2] = {start_rig(sweep_args(seeds[0], dir), out[0]), start_rig(sweep_args(seeds[1], dir), out[1])};
    const int code[2] = {exit_code(pid[0]), exit_code(pid[1])};
    const std::string said[2] = {slurp(out[0]), slurp(out[1])};
    INFO("race " << k << (same ? " (the same campaign)" : " (two campaigns)") << "\n--- a: exit " << code[0] << "\n"
                 << said[0] << "\n--- b: exit " << code[1] << "\n"
                 << said[1]);
    REQUIRE((code[0] == 0 || code[1] == 0));
    const int won = code[0] == 0 ? 0 : 1, lost = 1 - won;
    if (code[lost] == 2) {
      CHECK(said[lost].find(dir) != std::string::npos);
      if (said[lost].find("is being written by another process (pid " + std::to_string(pid[won]) + ": ") !=
          std::string::npos) {
        ++busy;
      } else {
        // Not overlapping: the first had finished before the second took the directory.
        CHECK(!same);
        CHECK(said[lost].find(dir + " holds another campaign: its runs") == std::string::npos);
        CHECK(said[lost].find(dir + " holds another campaign: its ") != std::string::npos);
        ++other;
      }
    } else {
      // Both 0: the same campaign, the second finding it finished and resuming it (nothing to fly).
      REQUIRE(same);
      CHECK(code[lost] == 0);
      CHECK(said[lost].find("resuming " + dir + ": 0 of 3 runs without a result") != std::string::npos);
      ++resumed;
    }
    // What is left is the winner's campaign, whole: its three runs, its seeds only, each result file
    // read back through the campaign's check (collect), the same merged rows.
    const int first = std::stoi(seeds[won]);
    const std::multiset<int> want = {first, first + 1, first + 2};
    const std::multiset<int> got = result_seeds(dir);
    CHECK(got == want);
    CHECK(files_in(dir + "/runs") == 3);
    const std::string csv = nimble::test::csv_without_machine(dir + "/result.csv");
    const auto collect = run_rig("sweep collect " + dir + " --no-progress");
    INFO(collect.out << collect.err);
    CHECK(collect.exit_code == 0);
    CHECK(nimble::test::csv_without_machine(dir + "/result.csv") == csv);
    intact += got == want && collect.exit_code == 0;
  }
  std::printf(
      "campaign race: 20 races of two rig sweep --dir: %d refused at once as held (exit 2, the holder's pid "
      "named), %d refused as another campaign (exit 2), %d resumed a finished campaign (exit 0); %d of 20 "
      "campaigns left whole with only their own runs\n",
      busy, other, resumed, intact);
  CHECK(busy + other + resumed == 20);
  CHECK(intact == 20);
}

TEST_CASE(
    "campaign directory: a user's directory or a stray result file is refused untouched by rig sweep, "
    "rig reproduce thesis --dir and rig discrepancy --power --dir",
    "[resource]") {
  const std::string d = nimble::test::scratch_dir("campaign_foreign");
  const std::string user = d + "/user";
  fs::create_directories(user);
  const std::string mine = "name: mine\n# the user's own scenario, not a campaign's\n";
  std::ofstream(user + "/scenario.yaml") << mine;
  const std::string stray = d + "/stray";
  fs::create_directories(stray + "/runs");
  const std::string stray_run = "{\"index\": 1, \"seed\": 2, \"report\": null, \"failure\": \"not flown here\"}\n";
  std::ofstream(stray + "/runs/run-000001.json") << stray_run;

  const std::vector<std::string> commands = {
      kSweep + " --seeds 1-3",
      "reproduce thesis --seeds 1 --no-progress --logs " + d + "/logs",
      "discrepancy --power --scenario " + kSource + "rig_configs/cl_doublet_train_slow.yaml --model " + kSource +
          "rig_configs/models/nimble_lateral_set1_kinematic.yaml --effect actuator_delay=0.006 --flights 1 --lengths 9 "
          "--refine 0 --no-progress",
  };
  for (const std::string& command : commands) {
    for (const auto& [dir, holds] :
         {std::pair{user, std::string("it holds scenario.yaml")}, std::pair{stray, std::string("it holds runs/")}}) {
      INFO(command << " --dir " << dir);
      const auto r = run_rig(command + " --dir " + dir);
      INFO(r.out << r.err);
      CHECK(r.exit_code == 2);
      CHECK(r.err.find(dir + " is not empty and holds no campaign (no campaign.json; " + holds) != std::string::npos);
      CHECK(!fs::exists(dir + "/campaign.json"));
    }
    CHECK(slurp(user + "/scenario.yaml") == mine);
    CHECK(files_in(user) == 1);
    CHECK(slurp(stray + "/runs/run-000001.json") == stray_run);
    CHECK(files_in(stray + "/runs") == 1);
  }
}

TEST_CASE(
    "campaign directory: a result file copied from another campaign is refused, named, and the campaign's own "
    "read back whole once it is gone",
    "[resource]") {
  const std::string d = nimble::test::scratch_dir("campaign_copied");
  // Two campaigns with the same options, made apart: each its own identity.
  for (const char* c : {"/c1", "/c2"}) {
    const auto r = run_rig(kSweep + " --seeds 1-3 --dir " + d + c);
    INFO(r.out << r.err);
    REQUIRE(r.exit_code == 0);
  }
  const std::string own = d + "/c1/runs/run-000001.json", kept = d + "/own.json";
  const std::string csv = nimble::test::csv_without_machine(d + "/c1/result.csv");
  fs::copy_file(own, kept);
  fs::copy_file(d + "/c2/runs/run-000001.json", own, fs::copy_options::overwrite_existing);
  for (const std::string& args :
       {"sweep collect " + d + "/c1 --no-progress", "sweep --resume " + d + "/c1 --no-progress",
        kSweep + " --seeds 1-3 --dir " + d + "/c1"}) {
    INFO(args);
    const auto r = run_rig(args);
    INFO(r.out << r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(own + " is not a result of this campaign: it is a result of another campaign") !=
          std::string::npos);
  }
  fs::copy_file(kept, own, fs::copy_options::overwrite_existing);
  // A file in runs/ that is no result file at all.
  std::ofstream(d + "/c1/runs/notes.txt") << "mine\n";
  const auto notes = run_rig("sweep collect " + d + "/c1 --no-progress");
  CHECK(notes.exit_code == 2);
  CHECK(notes.err.find(d + "/c1/runs/notes.txt is not a result file of a campaign") != std::string::npos);
  CHECK(slurp(d + "/c1/runs/notes.txt") == "mine\n");
  fs::remove(d + "/c1/runs/notes.txt");

  const auto whole = run_rig("sweep collect " + d + "/c1 --no-progress");
  INFO(whole.out << whole.err);
  CHECK(whole.exit_code == 0);
  CHECK(nimble::test::csv_without_machine(d + "/c1/result.csv") == csv);
}

TEST_CASE(
    "campaign directory: a directory held by another process is refused at once by every campaign, naming it "
    "and the holder's pid, and once the holder is killed the next campaign takes it",
    "[resource]") {
  const std::string d = nimble::test::scratch_dir("campaign_held");
  const std::string dir = d + "/c";
  int ready[2];
  REQUIRE(::pipe(ready) == 0);
  const pid_t holder = ::fork();
  REQUIRE(holder >= 0);
  if (holder == 0) {
    ::close(ready[0]);
    try {
      const nimble::OutputLock lock = nimble::OutputLock::directory(dir, "the campaign directory");
      (void)!::write(ready[1], "1", 1);
      for (;;) ::pause();
    } catch (...) {
    }
    ::_exit(1);
  }
  ::close(ready[1]);
  char byte = 0;
  REQUIRE(::read(ready[0], &byte, 1) == 1);
  ::close(ready[0]);
  const std::string held =
      "the campaign directory " + dir + " is being written by another process (pid " + std::to_string(holder);
  for (const std::string& command : {
           kSweep + " --seeds 1-3",
           "reproduce thesis --seeds 1 --no-progress --logs " + d + "/logs",
           "discrepancy --power --scenario " + kSource + "rig_configs/cl_doublet_train_slow.yaml --model " + kSource +
               "rig_configs/models/nimble_lateral_set1_kinematic.yaml --effect actuator_delay=0.006 --flights 1 "
               "--lengths 9 --refine 0 --no-progress",
       }) {
    INFO(command);
    const auto r = run_rig(command + " --dir " + dir);
    INFO(r.out << r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.err.find(held) != std::string::npos);
    CHECK(fs::is_empty(dir));
  }
  ::kill(holder, SIGKILL);
  ::waitpid(holder, nullptr, 0);
  const auto r = run_rig(kSweep + " --seeds 1-3 --dir " + dir);
  INFO(r.out << r.err);
  CHECK(r.exit_code == 0);
  CHECK(result_seeds(dir) == std::multiset<int>{1, 2, 3});
}
