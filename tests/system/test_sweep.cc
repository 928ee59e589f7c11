// System tests of `rig sweep`: a small campaign in process (two parameter sets, three seeds,
// two jobs) gives per-run verdicts that match single `rig run`s, a JSON runs list and a CSV;
// bad input stops it before any run, naming the problem; a run that is not ok makes exit 1;
// a campaign directory survives its launcher being killed and is finished by --resume.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <map>
#include <string>
#include <thread>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/campaign_files.h"
#include "../support/lock_wait.h"
#include "../support/rig_runs.h"

using nimble::test::rig_run;
using nimble::test::slurp;

namespace {

const std::string kSource = std::string(RIG_SOURCE_DIR) + "/";
const std::string kScenario = kSource + "rig_configs/id_doublet_train_fast.yaml";

struct SweepOutcome {
  int exit_code = -1;
  std::string output;
};

SweepOutcome rig_sweep(const std::string& dir, const std::string& args) {
  const std::string out = dir + "/sweep.txt";
  const std::string cmd = std::string(RIG_BIN) + " sweep " + args + " --no-progress >" + out + " 2>&1";
  const int status = std::system(cmd.c_str());
  return {WIFEXITED(status) ? WEXITSTATUS(status) : -1, slurp(out)};
}

}  // namespace

TEST_CASE("rig sweep: two model sets x three seeds, each run as a single run would fly it", "[system]") {
  const std::string d = nimble::test::scratch_dir("sweep_ok");
  const std::string set1 = kSource + "rig_configs/models/nimble_lateral_set1.yaml";
  const std::string set4 = kSource + "rig_configs/models/nimble_lateral_set4.yaml";
  const SweepOutcome s = rig_sweep(d, kScenario + " --seeds 4-6 --vary model=" + set1 + "," + set4 +
                                          " --set pilot.enabled=false --jobs 2 --json " + d + "/sweep.json --csv " + d +
                                          "/sweep.csv --logs " + d + "/logs");
  INFO(s.output);
  REQUIRE(s.exit_code == 0);
  CHECK(s.output.find("6 runs: 2 parameter sets x 3 seeds (4-6), clock inprocess, 2 jobs") != std::string::npos);
  CHECK(s.output.find("controlled 3/3 (100 %)") != std::string::npos);
  const YAML::Node j = YAML::LoadFile(d + "/sweep.json");
  REQUIRE(j["runs"].size() == 6);
  REQUIRE(j["sets"].size() == 2);
  CHECK(j["sets"][1]["label"].as<std::string>() == "model=" + set4);
  for (const auto& run : j["runs"]) {
    CHECK(run["result"].as<std::string>() == "ok");
    CHECK(run["sim_time_s"].as<double>() == Approx(6.0));
  }
  // Set 4 rolls further than set 1 on the same doublets (its roll damping is lower).
  CHECK(j["sets"][1]["percentiles"]["max_abs_phi_deg"]["p50"].as<double>() >
        j["sets"][0]["percentiles"]["max_abs_phi_deg"]["p50"].as<double>() + 5.0);
  const std::string csv = slurp(d + "/sweep.csv");
  CHECK(std::count(csv.begin(), csv.end(), '\n') == 7);
  CHECK(std::filesystem::exists(d + "/logs/set2-seed5.lcmlog"));

  // Run 5 of set 2 is the single run with that model and seed.
  const std::string r = nimble::test::scratch_dir("sweep_single");
  const auto single = rig_run(kScenario, r, "--clock inprocess --seed 5 --set pilot.enabled=false --set model=" + set4);
  REQUIRE(single.exit_code == 0);
  const YAML::Node run5 = j["runs"][4];
  REQUIRE(run5["seed"].as<int>() == 5);
  CHECK(run5["figures"]["max_abs_phi_deg"].as<double>() ==
        Approx(single.summary["max_abs"]["phi"].as<double>() * 180.0 / M_PI).epsilon(1e-12));
  CHECK(nimble::test::differing(nimble::test::truth_payloads(d + "/logs/set2-seed5.lcmlog"),
                                nimble::test::truth_payloads(r + "/run.lcmlog")) == 0);
}

TEST_CASE("rig sweep: a run that is not controlled makes exit 1 and is listed with its seed", "[system]") {
  const std::string d = nimble::test::scratch_dir("sweep_bad_run");
  // A roll limit of 5 deg: the first doublet breaks it.
  const SweepOutcome s = rig_sweep(
      d, kScenario + " --seeds 1-2 --set duration_s=3 --set summary.max_phi_deg=5 --json " + d + "/sweep.json");
  INFO(s.output);
  CHECK(s.exit_code == 1);
  CHECK(s.output.find("controlled 0/2") != std::string::npos);
  CHECK(s.output.find("seed 2: completed, vehicle NOT controlled") != std::string::npos);
  CHECK(YAML::LoadFile(d + "/sweep.json")["runs"][0]["exit_code"].as<int>() == 1);
}

TEST_CASE("rig sweep: bad input stops it before any run, naming the problem", "[system]") {
  const std::string d = nimble::test::scratch_dir("sweep_bad");
  SweepOutcome s = rig_sweep(d, kScenario + " --seeds 5-1");
  CHECK(s.exit_code == 2);
  CHECK(s.output.find("--seeds needs A-B") != std::string::npos);
  s = rig_sweep(d, kScenario);
  CHECK(s.exit_code == 2);
  CHECK(s.output.find("--seeds is required") != std::string::npos);
  s = rig_sweep(d, kScenario + " --seeds 1-3 --vary plant.rate_hz=1000,-3");
  CHECK(s.exit_code == 2);
  CHECK(s.output.find("plant.rate_hz") != std::string::npos);
  CHECK(s.output.find("parameter set 'plant.rate_hz=-3'") != std::string::npos);
  CHECK(s.output.find("runs:") == std::string::npos);  // nothing flew
  s = rig_sweep(d, kScenario + " --seeds 1-3 --jobs 0");
  CHECK(s.exit_code == 2);
  CHECK(s.output.find("--jobs") != std::string::npos);
}

namespace {

std::size_t count_run_files(const std::string& campaign) {
  std::size_t n = 0;
  std::error_code ec;
  for (const auto& e : std::filesystem::directory_iterator(campaign + "/runs", ec)) {
    const std::string name = e.path().filename().string();
    n += name.size() == 15 && name.rfind("run-", 0) == 0;
  }
  return n;
}

}  // namespace

TEST_CASE("rig sweep: a campaign whose launcher was killed is finished by --resume, nothing lost or flown twice",
          "[system]") {
  const std::string d = nimble::test::scratch_dir("sweep_resume");
  const std::string c = d + "/campaign";
  const std::string args = kScenario + " --seeds 1-24 --set duration_s=4 --set pilot.enabled=false";
  // The launcher, one run at a time, killed once some runs have their result.
  const pid_t rig = ::fork();
  if (rig == 0) {
    std::freopen((d + "/killed.txt").c_str(), "w", stderr);
    ::execl(RIG_BIN, RIG_BIN, "sweep", kScenario.c_str(), "--seeds", "1-24", "--set", "duration_s=4", "--set",
            "pilot.enabled=false", "--jobs", "1", "--dir", c.c_str(), "--no-progress", static_cast<char*>(nullptr));
    ::_exit(127);
  }
  const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
  while (count_run_files(c) < 5 && std::chrono::steady_clock::now() < give_up) {
    std::this_thread::sleep_for(std::chrono::milliseconds(5));
  }
  ::kill(rig, SIGKILL);
  ::waitpid(rig, nullptr, 0);
  INFO(slurp(d + "/killed.txt"));
  // Its workers hold the campaign's lock until the kernel has ended them too (they die with the
  // launcher, PR_SET_PDEATHSIG); on a loaded machine that is a moment after the launcher.
  REQUIRE(nimble::test::wait_for_no_holder(c, std::chrono::seconds(30)));
  const std::size_t finished = count_run_files(c);
  REQUIRE(finished >= 5);
  REQUIRE(finished < 24);
  // What a writer killed mid-file leaves: a temporary name, never merged, removed on resume.
  { std::ofstream(c + "/runs/run-000023.json.host.1.partial") << "{\"index\": 23, \"rep"; }
  std::map<std::string, std::filesystem::file_time_type> before;
  for (const auto& e : std::filesystem::directory_iterator(c + "/runs")) {
    if (e.path().extension() == ".json") before[e.path().filename().string()] = e.last_write_time();
  }
  SweepOutcome collect = rig_sweep(d, "collect " + c);
  CHECK(collect.exit_code == 3);
  CHECK(collect.output.find(std::to_string(24 - before.size()) + " of 24 runs have no result") != std::string::npos);

  const SweepOutcome resumed = rig_sweep(d, "--resume " + c + " --jobs 2");
  INFO(resumed.output);
  REQUIRE(resumed.exit_code == 0);
  CHECK(resumed.output.find("resuming " + c + ": " + std::to_string(24 - before.size()) +
                            " of 24 runs without a result") != std::string::npos);
  CHECK(!std::filesystem::exists(c + "/runs/run-000023.json.host.1.partial"));
  CHECK(count_run_files(c) == 24);
  for (const auto& [name, time] : before) {
    INFO(name);
    CHECK(std::filesystem::last_write_time(c + "/runs/" + name) == time);
  }
  // The same result as the campaign flown in one go, two at a time.
  const SweepOutcome whole = rig_sweep(d, args + " --jobs 2 --dir " + d + "/whole");
  REQUIRE(whole.exit_code == 0);
  CHECK(nimble::test::json_without_machine(c + "/result.json") ==
        nimble::test::json_without_machine(d + "/whole/result.json"));
  CHECK(nimble::test::csv_without_machine(c + "/result.csv") ==
        nimble::test::csv_without_machine(d + "/whole/result.csv"));

  // A result file damaged afterwards (a full disk, a bad copy) is named, not merged.
  std::filesystem::resize_file(c + "/runs/run-000007.json", 40);
  collect = rig_sweep(d, "collect " + c);
  CHECK(collect.exit_code == 3);
  CHECK(collect.output.find("damaged result file " + c + "/runs/run-000007.json (set 1 seed 8)") != std::string::npos);
}

TEST_CASE("rig sweep: a campaign refuses to go on when its scenario or a file it names changed", "[system]") {
  const std::string d = nimble::test::scratch_dir("sweep_changed");
  const std::string model = d + "/model.yaml";
  {
    // Set 1's model, its vehicle named by absolute path.
    std::string text = slurp(kSource + "rig_configs/models/nimble_lateral_set1.yaml");
    const std::string vehicle = "../vehicles/nimble_no_wifi.yaml";
    REQUIRE(text.find(vehicle) != std::string::npos);
    text.replace(text.find(vehicle), vehicle.size(), kSource + "rig_configs/vehicles/nimble_no_wifi.yaml");
    std::ofstream(model) << text;
  }
  const SweepOutcome first =
      rig_sweep(d, kScenario + " --seeds 1-2 --set duration_s=2 --vary model=" + model + " --dir " + d + "/c");
  INFO(first.output);
  REQUIRE(first.exit_code == 0);
  std::filesystem::remove(d + "/c/runs/run-000001.json");
  { std::ofstream(model, std::ios::app) << "\n# edited after the campaign was made\n"; }
  const SweepOutcome resumed = rig_sweep(d, "--resume " + d + "/c");
  CHECK(resumed.exit_code == 2);
  CHECK(resumed.output.find("changed since the campaign was made (parameter set 1 'model=" + model + "'") !=
        std::string::npos);
  // Neither is a directory without a campaign, nor another campaign made in one directory.
  CHECK(rig_sweep(d, "--resume " + d).output.find("no campaign in " + d) != std::string::npos);
  const SweepOutcome again = rig_sweep(d, kScenario + " --seeds 1-2 --dir " + d + "/c");
  CHECK(again.exit_code == 2);
  CHECK(again.output.find(d + "/c holds another campaign: its overrides is [\"duration_s=2\"], this one's []") !=
        std::string::npos);
  // No Slurm client on this machine: said so, with the package that has it.
  const std::string path = std::getenv("PATH");
  ::setenv("PATH", "/nonexistent", 1);
  const SweepOutcome slurm = rig_sweep(d, kScenario + " --seeds 1-2 --backend slurm --dir " + d + "/s");
  ::setenv("PATH", path.c_str(), 1);
  INFO(slurm.output);
  CHECK(slurm.exit_code == 2);
  CHECK(slurm.output.find("sbatch not found: the slurm backend needs Slurm's client commands") != std::string::npos);
}
