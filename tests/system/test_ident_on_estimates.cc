// System test of the identification on what the lab measures: the identification doublet
// train flown in lockstep on the estimator (IMU and motion capture fused by the EKF, the
// controller flying on the estimate), the LCM log identified by `rig identify`, which takes
// the states from ESTIMATE. Checks the criteria against set 1 (thesis Table 9.2):
// the well-determined derivatives within 10 % and 3 sigma, Lv and L_dt less well
// determined, metrics of the order of the paper's Table 4; for seeds 1, 2 and 3.

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <map>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/fit_metrics.h"
#include "../support/rig_runs.h"
#include "core/model.h"

namespace fs = std::filesystem;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

/// Relative standard deviation (coloured-residual sigma) of one parameter of a report.
double rel_sigma_c(const YAML::Node& p, const std::string& name) {
  return p[name]["sigma_coloured"].as<double>() / std::fabs(p[name]["value"].as<double>());
}

}  // namespace

TEST_CASE("identification on the estimator: the set-1 derivatives from ESTIMATE, Table 3/4 criteria, seeds 1-3",
          "[system]") {
  // Three seeded flights (sensor noise, dropouts): the criteria hold for each, not for one chosen seed.
  const int seed = GENERATE(1, 2, 3);
  INFO("seed " << seed);
  const std::string dir = nimble::test::scratch_dir("ident_est_" + std::to_string(seed));
  const std::string log = dir + "/run.lcmlog", summary = dir + "/summary.json";
  // Explicit processes, controller input and seed: the test does not depend on the shipped defaults.
  const std::string fly =
      std::string(RIG_BIN) + " run " + kConfigs + "id_doublet_train_fast.yaml --clock lockstep" +
      " --set pilot.enabled=false" +  // the pilot off: Eq 21 subtracts a constant w0 p, and with the pilot w moves from w0 to 0 (docs/paper-flights.md "Flights like the paper's")
      " --seed " + std::to_string(seed) + " --set processes=[plant,controller,mocap,estimator]" +
      " --set run.controller_input=estimate --log " + log + " --json " + summary + " --no-progress >" + dir +
      "/run.txt 2>&1";
  const int status = std::system(fly.c_str());
  INFO(nimble::test::slurp(dir + "/run.txt"));
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  const YAML::Node s = YAML::LoadFile(summary);
  REQUIRE(s["controlled"].as<bool>());
  REQUIRE(s["estimator"]);  // the EKF ran and its estimate is in the log

  // The log's measured states are the estimates.
  const auto exported = nimble::test::run_rig("export " + log + " --csv " + dir + "/flight.csv");
  INFO(exported.err);
  REQUIRE(exported.exit_code == 0);
  CHECK(exported.out.find("(states from estimate)") != std::string::npos);

  const std::string json = dir + "/ident.json";
  const auto ident = nimble::test::run_rig("identify " + log + " --w0 -0.30 --json " + json);
  INFO(ident.err);
  REQUIRE(ident.exit_code == 0);
  const YAML::Node report = YAML::LoadFile(json);
  const YAML::Node p = report["parameters"];

  // Set 1 as the plant flies it (rig_configs/models/nimble_lateral_set1.yaml), which must be
  // thesis Table 9.2 data set 1.
  const YAML::Node model = YAML::LoadFile(kConfigs + "models/nimble_lateral_set1.yaml")["derivatives"];
  const std::map<std::string, double> table_9_2 = {{"Lp", -2.43e-4},  {"Lv", -3.74e-4}, {"L_df", 1.06e-4},
                                                   {"L_dt", 4.19e-5}, {"Yv", -5.61e-2}, {"Y_df", -8.63e-4}};
  std::map<std::string, double> set1;
  for (const auto& [name, value] : table_9_2) {
    set1[name] = model[name].as<double>();
    CHECK(set1[name] == Approx(value).epsilon(1e-9));
  }

  // Well-determined derivatives: within 10 % and within 3 sigma_c of set 1. sigma_c is the
  // report's Newey-West sigma, which allows for the coloured residuals of 9 Hz low-passed
  // data at 512 Hz (ident/README.md); the thesis's white-residual sigma is about 3-4x
  // smaller there, and the unit tests show that sigma_c, not sigma, matches the spread of
  // the estimates over repeated flights.
  for (const char* name : {"Lp", "L_df", "Yv", "Y_df"}) {
    const double value = p[name]["value"].as<double>(), sigma_c = p[name]["sigma_coloured"].as<double>();
    const double truth = set1.at(name);
    INFO(name << " = " << value << " (sigma " << p[name]["sigma"].as<double>() << ", sigma_c " << sigma_c << "), set 1 "
              << truth << ": " << 100.0 * (value - truth) / std::fabs(truth) << " %, "
              << std::fabs(value - truth) / sigma_c << " sigma_c");
    REQUIRE(sigma_c > 0.0);
    CHECK(std::fabs(value - truth) < 0.10 * std::fabs(truth));
    CHECK(std::fabs(value - truth) < 3.0 * sigma_c);
  }

  // Lv and L_dt: less well determined (thesis Table 3: 407 % and 131 % against Lp 70 % and
  // L_df 8 %); here, in the same roll equation, their relative sigma is larger than those of
  // Lp and L_df.
  for (const char* weak : {"Lv", "L_dt"}) {
    for (const char* strong : {"Lp", "L_df"}) {
      INFO(weak << " relative sigma_c " << rel_sigma_c(p, weak) << ", " << strong << " " << rel_sigma_c(p, strong));
      CHECK(rel_sigma_c(p, weak) > rel_sigma_c(p, strong));
    }
    CHECK(p[weak]["sigma"].as<double>() > 0.0);
  }

  // Metrics of the order of Table 4 (p_dot: r_xy 0.945, R^2 0.907, RMSE 5.74 % of range;
  // v_dot: 0.982, 0.967, 2.84 %).
  nimble::test::check_fit_metrics(report);

  // The estimate and the truth of the same flight give the same roll derivatives: the states
  // of ESTIMATE are placed at the IMU sample they describe (stamped at the estimator's
  // publication they lag delta_f by 1.5 ms and Lp comes out 15 % small).
  const auto truth_csv = nimble::test::run_rig("export " + log + " --states truth --csv " + dir + "/truth.csv");
  REQUIRE(truth_csv.exit_code == 0);
  const std::string truth_json = dir + "/ident_truth.json";
  const auto from_truth = nimble::test::run_rig("identify " + dir + "/truth.csv --w0 -0.30 --json " + truth_json);
  INFO(from_truth.err);
  REQUIRE(from_truth.exit_code == 0);
  const YAML::Node pt = YAML::LoadFile(truth_json)["parameters"];
  for (const char* name : {"Lp", "L_df"}) {
    const double est = p[name]["value"].as<double>(), tru = pt[name]["value"].as<double>();
    INFO(name << ": from the estimate " << est << ", from the truth " << tru);
    CHECK(std::fabs(est - tru) < 0.02 * std::fabs(tru));
  }
}

TEST_CASE(
    "discrepancy on the effect-free identification train: the kinematic term Eq 21 drops is named and Yp comes "
    "back to the plant's value",
    "[system]") {
  // The rig's own truth against the paper's linear model: the nonlinear plant has p w and
  // g sin(phi) in v_dot, Eq 21 linearises them at w0 while w drifts during the manoeuvre.
  const std::string dir = nimble::test::scratch_dir("discrepancy_id_train");
  const std::string log = dir + "/run.lcmlog";
  const std::string fly =
      std::string(RIG_BIN) + " run " + kConfigs + "id_doublet_train_fast.yaml --clock lockstep" +
      " --set pilot.enabled=false" +  // the pilot off: Eq 21 subtracts a constant w0 p, and with the pilot w moves from w0 to 0 (docs/paper-flights.md "Flights like the paper's")
      " --seed 1 --log " + log + " --no-progress >" + dir + "/run.txt 2>&1";
  const int status = std::system(fly.c_str());
  INFO(nimble::test::slurp(dir + "/run.txt"));
  REQUIRE(WIFEXITED(status));
  REQUIRE(WEXITSTATUS(status) == 0);
  const auto truth_csv = nimble::test::run_rig("export " + log + " --states truth --csv " + dir + "/truth.csv");
  REQUIRE(truth_csv.exit_code == 0);
  const double yp_plant = 2.75e-3;  // rig_configs/models/nimble_lateral_set1.yaml, flown by the plant
  for (const std::string& data : {log, dir + "/truth.csv"}) {
    INFO(data);
    const std::string json = dir + "/discrepancy.json", model_out = dir + "/augmented.yaml";
    const auto r =
        nimble::test::run_rig("discrepancy " + data + " --model " + kConfigs +
                              "models/nimble_lateral_set1.yaml --json " + json + " --model-out " + model_out);
    INFO(r.out << r.err);
    REQUIRE(r.exit_code == 0);
    const YAML::Node d = YAML::LoadFile(json);
    CHECK(d["verdict"].as<std::string>() == "effects");
    bool kinematic = false;
    for (const auto& e : d["effects"]) kinematic = kinematic || e["name"].as<std::string>() == "kinematic_coupling";
    CHECK(kinematic);
    const YAML::Node before = d["baseline"]["Yp"], after = d["augmented"]["Yp"];
    CHECK(std::fabs(before["value"].as<double>() - yp_plant) > 3.0 * before["sigma_coloured"].as<double>());
    CHECK(std::fabs(after["value"].as<double>() - yp_plant) < 3.0 * after["sigma_coloured"].as<double>());
    CHECK(d["gap"]["after"].as<double>() < 0.5 * d["gap"]["before"].as<double>());
    CHECK(nimble::load_model(model_out).effects.count("kinematic_coupling") == 1);
    // Flown in closed loop by the controller copy, the augmented model tracks v much better.
    for (const auto& c : d["closed_loop"]["outputs"]) {
      if (c["output"].as<std::string>() == "v") CHECK(c["r2_after"].as<double>() > c["r2_before"].as<double>() + 0.2);
    }
    CHECK(d["closed_loop"]["outputs"].size() == 4);
  }
}
