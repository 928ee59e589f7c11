// System tests of `rig sweep`: a small campaign in process (two parameter sets, three seeds,
// two jobs) gives per-run verdicts that match single `rig run`s, a JSON runs list and a CSV;
// bad input stops it before any run, naming the problem; a run that is not ok makes exit 1.

#include <sys/wait.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

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
                                          " --set pilot.enabled=false --jobs 2 --json " + d + "/sweep.json --csv " + d + "/sweep.csv --logs " +
                                          d + "/logs");
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
  const SweepOutcome s = rig_sweep(d, kScenario + " --seeds 1-2 --set duration_s=3 --set summary.max_phi_deg=5 --json " +
                                          d + "/sweep.json");
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
