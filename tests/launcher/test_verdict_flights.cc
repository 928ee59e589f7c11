// Functional tests of the roll tracking verdict on flights, in process: two loops that have lost
// their margin to actuator delay (hover in a +-31 deg limit cycle, the identification train
// swinging to the roll limit), once judged ok on their roll alone, are not ok and name their
// oscillation; the same scenarios with nominal settings stay ok.

#include <cmath>
#include <cstdio>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/rig_runs.h"
#include "launcher/run_plan.h"

using nimble::test::rig_run;
using nimble::test::RunResult;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

std::string delay(const std::string& seconds) {
  return " --set plant.effects.actuator_delay.enabled=true --set plant.effects.actuator_delay.delay_s=" + seconds;
}

RunResult fly(const std::string& scenario, const std::string& tag, const std::string& args) {
  const RunResult r =
      rig_run(kConfigs + scenario, nimble::test::scratch_dir("verdict_" + tag), "--clock inprocess " + args);
  const std::string result = r.summary ? r.summary["result"].as<std::string>() : "(no summary)";
  std::printf("%-24s %-40s exit %d: %s\n", scenario.c_str(), args.c_str(), r.exit_code, result.c_str());
  return r;
}

/// The oscillation a run's summary names.
YAML::Node oscillation_of(const RunResult& r) {
  REQUIRE(r.summary);
  REQUIRE(r.summary["tracking"]);
  return r.summary["tracking"]["oscillation"];
}

}  // namespace

TEST_CASE("verdict: hover with 14.3 ms of actuator delay rolls in a limit cycle: not ok, the oscillation named",
          "[launcher][verdict]") {
  // Within the roll limit (+-31 deg against 80): judged ok on the roll alone.
  const RunResult r = fly("hover.yaml", "hover_delay", "--set duration_s=20" + delay("0.0143"));
  INFO(r.output);
  CHECK(r.exit_code == nimble::launcher::kRunNotTracking);
  CHECK(r.summary["controlled"].as<bool>());
  const std::string result = r.summary["result"].as<std::string>();
  CHECK(result.rfind("completed, roll oscillation ", 0) == 0);
  const YAML::Node o = oscillation_of(r);
  CHECK(o["detected"].as<bool>());
  CHECK(o["kind"].as<std::string>() == "growing");  // from a degree to the limit cycle
  CHECK(o["frequency_hz"].as<double>() == Approx(2.1).margin(0.3));
  CHECK(o["amplitude_deg"].as<double>() == Approx(31.0).margin(3.0));
  CHECK(o["damping_ratio"].as<double>() < 0.0);
  CHECK(o["start_s"].as<double>() > 1.0);
  CHECK(o["start_s"].as<double>() < 8.0);
  CHECK(o["cycles"].as<int>() >= 20);
  CHECK(r.summary["tracking"]["lost"].as<bool>());
  // The limit cycle's error about the hover reference is the roll itself.
  CHECK(r.summary["tracking"]["max_deg"].as<double>() ==
        Approx(r.summary["max_abs"]["phi"].as<double>() * 180.0 / M_PI).epsilon(0.01));
}

TEST_CASE("verdict: the identification train with 30 ms of actuator delay is not ok and names its oscillation",
          "[launcher][verdict]") {
  // Seed 2 stays within the roll limit (79 deg, judged ok on the roll alone); seed 1 passes it.
  for (const int seed : {1, 2}) {
    const RunResult r =
        fly("id_doublet_train_fast.yaml", "id_delay", "--seed " + std::to_string(seed) + delay("0.030"));
    INFO("seed " << seed << "\n" << r.output);
    REQUIRE(r.summary);
    const bool controlled = r.summary["controlled"].as<bool>();
    CHECK(controlled == (seed == 2));
    CHECK(r.exit_code == (controlled ? nimble::launcher::kRunNotTracking : nimble::launcher::kRunNotControlled));
    CHECK(r.summary["result"].as<std::string>().find("roll oscillation 1.5 Hz") != std::string::npos);
    const YAML::Node o = oscillation_of(r);
    CHECK(o["detected"].as<bool>());
    CHECK(o["frequency_hz"].as<double>() == Approx(1.5).margin(0.2));
    CHECK(o["amplitude_deg"].as<double>() > 50.0);
    CHECK(std::fabs(o["damping_ratio"].as<double>()) < 0.005);  // neither decaying nor growing: a limit cycle
    CHECK(r.summary["tracking"]["rms_deg"].as<double>() > 30.0);
  }
}

TEST_CASE("verdict: hover and the identification train with nominal settings stay ok, their tracking within bounds",
          "[launcher][verdict]") {
  const nimble::launcher::JudgeConfig jc;
  for (const std::string scenario : {"hover.yaml", "id_doublet_train_fast.yaml"}) {
    for (const int seed : {1, 2, 3}) {
      const RunResult r = fly(scenario, "nominal", "--seed " + std::to_string(seed));
      INFO(scenario << " seed " << seed << "\n" << r.output);
      REQUIRE(r.summary);
      CHECK(r.exit_code == nimble::launcher::kRunOk);
      CHECK(r.summary["result"].as<std::string>() == "ok");
      const YAML::Node t = r.summary["tracking"];
      REQUIRE(t);
      CHECK(t["samples"].as<int>() > 3000);  // every control cycle: 512 Hz for 6 s or more
      CHECK_FALSE(t["lost"].as<bool>());
      CHECK_FALSE(t["oscillation"]["detected"].as<bool>());
      CHECK(t["rms_deg"].as<double>() < jc.max_tracking_rms_deg);
      CHECK(t["max_deg"].as<double>() < jc.max_tracking_error_deg);
      // The train moves the reference: its error is that of a loop that follows it (9 deg RMS).
      CHECK(t["rms_deg"].as<double>() > (scenario == "hover.yaml" ? 0.05 : 5.0));
    }
  }
}
