// The discrepancy workflow's open world on a rig flight (discrepancy/discrepancy.h, "Terms"): an effect
// the library does not have, flown by the plant as a generic term (plant.terms), is found by
// rig discrepancy as a term with its form, not given a library name; written into the model by
// --model-out; and the model with it predicts the flight better (rig validate).

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>

#include <unistd.h>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "core/model.h"
#include "synthetic_flight.h"
#include "../support/run_rig.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using namespace nimble;

namespace {

fs::path work_dir() { return fs::path(nimble::test::scratch_file("test_open_world", "")).parent_path(); }

/// A 24 s identification flight: the 7 and 4 Hz train's doublets and two slower ones, four times
/// over (one 6 s train holds too few independent blocks for the term's confirmation through the
/// excitation), as a manoeuvre and a scenario in `dir` on the shipped plant, controller and model.
std::string long_train_scenario(const fs::path& dir) {
  const std::string manoeuvre = (dir / "long_train.yaml").string();
  std::ofstream m(manoeuvre);
  m << "name: long_train\nsource: \"four identification trains of 7, 4, 2 and 5 Hz doublets\"\ngain_set: fast\n"
       "throttle_factor: auto\nsegments:\n  - {kind: hold, name: hover_before, duration_s: 1.0}\n";
  int i = 0;
  for (int rep = 0; rep < 4; ++rep) {
    for (const auto& [f, a] :
         {std::pair{7.0, 35.0}, std::pair{4.0, 25.0}, std::pair{2.0, 15.0}, std::pair{5.0, 30.0}}) {
      ++i;
      m << "  - {kind: doublet, name: d" << i << ", axis: roll, main_frequency_hz: " << f << ", amplitude_deg: " << a
        << "}\n  - {kind: hold, name: h" << i << ", duration_s: 0.5}\n";
    }
  }
  m.close();
  std::string text = test::slurp(ident::test::kConfigs + "id_doublet_train_fast.yaml");
  const auto replace = [&text](const std::string& from, const std::string& to) {
    const auto at = text.find(from);
    REQUIRE(at != std::string::npos);
    text.replace(at, from.size(), to);
  };
  replace("duration_s: 6.0", "duration_s: 24.0");
  replace("manoeuvre: manoeuvres/id_doublet_train_7_4hz.yaml", "manoeuvre: " + manoeuvre);
  for (const char* key : {"model: models/", "  base: plant/", "  base: controller/", "  base: run/", "  base: sensing/",
                          "  base: pilot/"}) {
    const std::string k = key;
    const std::string folder = k.substr(k.find(": ") + 2);
    replace(k, k.substr(0, k.find(": ") + 2) + ident::test::kConfigs + folder);
  }
  const std::string scenario = (dir / "long_train_scenario.yaml").string();
  std::ofstream(scenario) << text;
  return scenario;
}

}  // namespace

TEST_CASE(
    "an asymmetric flap effectiveness flown by the plant is found by rig discrepancy as the term pos(delta_f) in "
    "L, not named a sensor bias, written into the model, and the model with it predicts the flight better",
    "[cli][terms][open_world][heavy]") {
  const fs::path dir = work_dir();
  const std::string log = (dir / "asym.lcmlog").string();
  const double truth = 3.5e-5;  // N m per rad/s: a third of set 1's L_df more for delta_f > 0
  using test::run_rig;
  const auto flight =
      run_rig("run " + long_train_scenario(dir) + " --clock inprocess --seed 1 --log " + log +
              " --set 'plant.terms=[{equation: L, expression: \"pos(delta_f)\", coefficient: 3.5e-5}]'");
  INFO(flight.out << flight.err);
  REQUIRE(flight.exit_code == 0);

  const std::string set1 = ident::test::kConfigs + "models/nimble_lateral_set1.yaml";
  const std::string augmented = (dir / "augmented.yaml").string(), report = (dir / "report.json").string();
  const auto d = run_rig("discrepancy " + log + " --model " + set1 + " --model-out " + augmented + " --json " + report);
  INFO(d.out << d.err);
  REQUIRE(d.exit_code == 0);
  const YAML::Node j = YAML::LoadFile(report);
  REQUIRE(j["verdict"].as<std::string>() == "effects");
  // The term, with its form, coefficient and interval; no sensor bias (the library effect a
  // constant part of the asymmetry would otherwise be taken for).
  YAML::Node term;
  for (const YAML::Node& e : j["effects"]) {
    CHECK(e["name"].as<std::string>() != "sensor_bias");
    if (e["name"].as<std::string>() == "term") term = e;
  }
  REQUIRE(term);
  CHECK(term["equation"].as<std::string>() == "L");
  CHECK(term["expression"].as<std::string>() == "pos(delta_f)");
  const double c = term["coefficient"].as<double>();
  const double lo = term["interval"][0].as<double>(), hi = term["interval"][1].as<double>();
  INFO("pos(delta_f) in L: " << c << " [" << lo << ", " << hi << "], flown " << truth);
  CHECK(lo < c);
  CHECK(c < hi);
  CHECK(std::fabs(c - truth) < 0.15 * truth);
  // The library effects it was told from, each with its reason; sensor_bias by its signature.
  bool bias_ruled_out = false;
  for (const YAML::Node& r : term["ruled_out"]) {
    CHECK_FALSE(r["reason"].as<std::string>().empty());
    if (r["name"].as<std::string>() == "sensor_bias") {
      bias_ruled_out = r["reason"].as<std::string>().find("signature") != std::string::npos;
    }
  }
  CHECK(bias_ruled_out);
  // The gap in the term's own band shrinks.
  bool band = false;
  for (const YAML::Node& b : j["gap"]["bands"]) {
    if (b["name"].as<std::string>() != "term L:pos(delta_f)") continue;
    band = true;
    CHECK(b["after"].as<double>() < 0.5 * b["before"].as<double>());
  }
  CHECK(band);

  // --model-out carries the term, and the model with it predicts the flight's roll better than
  // the model as given.
  const DerivativeModel aug = load_model(augmented);
  REQUIRE(aug.terms.size() == 1);
  CHECK(aug.terms[0].equation == "L");
  CHECK(aug.terms[0].expression.to_string() == "pos(delta_f)");
  CHECK(aug.terms[0].coefficient == Approx(c).epsilon(1e-8));
  const auto v_aug = run_rig("validate " + augmented + " " + log + " --json -");
  const auto v_set1 = run_rig("validate " + set1 + " " + log + " --json -");
  INFO(v_aug.err << v_set1.err);
  REQUIRE(v_aug.exit_code == 0);
  REQUIRE(v_set1.exit_code == 0);
  const double rmse_aug = YAML::Load(v_aug.out)["metrics"]["p_dot"]["rmse"].as<double>();
  const double rmse_set1 = YAML::Load(v_set1.out)["metrics"]["p_dot"]["rmse"].as<double>();
  INFO("p_dot RMSE: augmented model " << rmse_aug << ", set 1 as given " << rmse_set1);
  CHECK(rmse_aug < 0.7 * rmse_set1);
  fs::remove_all(dir);
}

TEST_CASE(
    "a flap whose rate is limited, flown by the plant, is found by rig discrepancy as ratelimit(delta_f, r) in L "
    "with the flown limit inside r's interval and no library name, and --test-term reports the form as given",
    "[cli][terms][open_world]") {
  // The data-compatibility train (three 7 and 4 Hz identification trains, 18 s): the flapping-
  // frequency difference moves at up to about 1,400 rad/s^2, so a limit of 900 acts in the fast
  // parts of the doublets only. The plant's forces see the limited input, the log the actuator's.
  const fs::path dir = work_dir();
  const std::string log = (dir / "ratelimit.lcmlog").string(), report = (dir / "ratelimit.json").string();
  const double limit = 900.0;  // rad/s per s
  const std::string form = "\"ratelimit(delta_f, 900) - delta_f\"";
  using test::run_rig;
  const auto flight =
      run_rig("run " + ident::test::kConfigs + "compat_doublet_train.yaml --clock inprocess --seed 1 --log " + log +
              " --set pilot.enabled=false --set sensing.imu.vibration_enabled=false" +
              " --set 'plant.terms=[{equation: L, expression: " + form + ", coefficient: 1.06e-4}, " +
              "{equation: Y, expression: " + form + ", coefficient: -8.63e-4}]'");
  INFO(flight.out << flight.err);
  REQUIRE(flight.exit_code == 0);
  const std::string model = ident::test::kConfigs + "models/nimble_lateral_set1_kinematic.yaml";
  const auto d = run_rig("discrepancy " + log + " --model " + model +
                         " --test-term 'L: ratelimit(delta_f, 900)' --json " + report);
  INFO(d.out << d.err);
  REQUIRE(d.exit_code == 0);
  const YAML::Node j = YAML::LoadFile(report);
  REQUIRE(j["verdict"].as<std::string>() == "effects");
  YAML::Node term;
  for (const YAML::Node& e : j["effects"]) {
    CHECK(e["name"].as<std::string>() == "term");  // no library name
    if (e["name"].as<std::string>() == "term" && e["equation"].as<std::string>() == "L") term = e;
  }
  REQUIRE(term);
  CHECK(term["expression"].as<std::string>().rfind("ratelimit(delta_f, ", 0) == 0);
  const double r = term["parameters"]["r"].as<double>(), lo = term["parameters"]["r_lo"].as<double>(),
               hi = term["parameters"]["r_hi"].as<double>();
  INFO("r " << r << " [" << lo << ", " << hi << "], flown " << limit);
  CHECK(lo <= limit);
  CHECK(limit <= hi);
  CHECK(hi - lo < 0.2 * limit);  // an interval, not the scan's range
  // The coefficient is the flap's whole effectiveness, acting through the limit (set 1's L_df).
  CHECK(term["coefficient"].as<double>() == Approx(1.06e-4).epsilon(0.15));
  // The form tested as given: one test, far beyond any level.
  REQUIRE(j["term_tests"].size() == 1);
  CHECK(j["term_tests"][0]["expression"].as<std::string>() == "ratelimit(delta_f, 900)");
  CHECK(j["term_tests"][0]["p_value"].as<double>() < 1e-10);
  fs::remove_all(dir);
}
