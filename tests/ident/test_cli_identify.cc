// Functional tests of `rig identify` and `rig validate`: the real executable
// on a synthetic flight written as CSV, its JSON, model file, plots and errors.

#include <sys/wait.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <utility>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "core/model.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"
#include "ident/synthetic.h"
#include "discrepancy_generator.h"
#include "synthetic_flight.h"
#include "../support/run_rig.h"
#include "tests/support/scratch.h"

namespace fs = std::filesystem;
using namespace nimble;
using namespace nimble::ident;

namespace {

fs::path work_dir() { return fs::path(nimble::test::scratch_file("test_cli_identify", "")).parent_path(); }

using nimble::test::run_rig;
using nimble::test::slurp;
using Result = nimble::test::RigResult;

/// A synthetic set-1 identification flight as CSV (written once per process).
std::string flight_csv() {
  static const std::string path = [] {
    const DerivativeModel truth = ident::test::set1_model();
    const Vehicle vehicle = load_vehicle(truth.vehicle_file);
    const std::string file = (work_dir() / "flight.csv").string();
    write_flight_csv(simulate_synthetic(truth, vehicle, ident::test::identification_flight(7)), file);
    return file;
  }();
  return path;
}

}  // namespace

TEST_CASE("rig identify writes JSON with parameters, metrics, eigenvalues and whiteness", "[cli]") {
  const fs::path dir = work_dir();
  const std::string json = (dir / "ident.json").string(), model = (dir / "ident_model.yaml").string();
  const Result r = run_rig("identify " + flight_csv() + " --w0 -0.30 --json " + json + " --model-out " + model);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  for (const char* part : {"parameters", "Lp", "L_df", "sigma_c", "accuracy", "p_dot", "v_dot_star",
                           "residual whiteness", "eigenvalues", "UNSTABLE", "state PSDs", "model written to"}) {
    INFO(part);
    CHECK(r.out.find(part) != std::string::npos);
  }
  const YAML::Node j = YAML::LoadFile(json);
  CHECK(j["structure"].as<std::string>() == "lateral3");
  CHECK(j["method"].as<std::string>() == "wls");
  const DerivativeModel truth = ident::test::set1_model();
  for (const char* name : {"Lp", "Lv", "L_df", "L_dt", "Yp", "Yv", "Y_df", "Y_dt"}) {
    INFO(name);
    REQUIRE(j["parameters"][name]);
    CHECK(j["parameters"][name]["sigma"].as<double>() > 0.0);
  }
  CHECK(j["parameters"]["L_df"]["value"].as<double>() == Approx(truth.at("L_df")).epsilon(0.1));
  CHECK(j["parameters"]["Yv"]["value"].as<double>() == Approx(truth.at("Yv")).epsilon(0.1));
  for (const char* out : {"p_dot", "v_dot_star"}) {
    INFO(out);
    CHECK(j["metrics"][out]["rxy"].as<double>() > 0.99);
    CHECK(j["metrics"][out]["r2"].as<double>() > 0.99);
    CHECK(j["metrics"][out]["rmse"].as<double>() > 0.0);
    CHECK(j["metrics"][out]["rmse_pct_range"].as<double>() < 5.0);
    CHECK(j["whiteness"][out].as<double>() <= 0.1);
  }
  REQUIRE(j["eigenvalues"].size() == 3);
  for (const auto& pair : j["eigenvalues"]) CHECK(pair.size() == 2);
  // Appendix H's form: each equation's |rho| above the diagonal in the text, the JSON's matrix.
  const YAML::Node rho = j["correlation"]["L"];
  REQUIRE(rho["parameters"][0].as<std::string>() == "Lp");
  REQUIRE(rho["parameters"][1].as<std::string>() == "Lv");
  const double lp_lv = std::fabs(rho["matrix"][0][1].as<double>());
  CHECK(std::fabs(rho["matrix"][1][0].as<double>()) == Approx(lp_lv));
  char row[96];
  std::snprintf(row, sizeof row, "  %-12s %10.4f %10.4f", "Lp", 1.0, lp_lv);
  INFO(r.out);
  CHECK(r.out.find("parameter correlation matrices (|rho|, per equation; thesis Appendix H)") != std::string::npos);
  CHECK(r.out.find(row) != std::string::npos);
  // The model file flies: load_model reads it and its eigenvalues are those of the JSON.
  const DerivativeModel back = load_model(model);
  CHECK(back.at("L_df") == Approx(j["parameters"]["L_df"]["value"].as<double>()).epsilon(1e-8));
  CHECK(back.trim.w0_mps == Approx(-0.30));
  CHECK(j["model_out"].as<std::string>() == model);
}

TEST_CASE("rig identify --method ols --json - prints only JSON", "[cli]") {
  const Result r = run_rig("identify " + flight_csv() + " --method ols --order 8 --cutoff 10 --json -");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const YAML::Node j = YAML::Load(r.out);
  CHECK(j["method"].as<std::string>() == "ols");
  CHECK(j["processing"]["filter_order"].as<int>() == 8);
  CHECK(j["processing"]["cutoff_hz"].as<double>() == 10.0);
  CHECK(j["processing"]["interpolation"].as<std::string>() == "cubic");
  const Result linear = run_rig("identify " + flight_csv() + " --interpolation linear --json -");
  REQUIRE(linear.exit_code == 0);
  CHECK(YAML::Load(linear.out)["processing"]["interpolation"].as<std::string>() == "linear");
  const Result text = run_rig("identify " + flight_csv() + " --interpolation linear");
  CHECK(text.out.find("processing linear resampling") != std::string::npos);
}

TEST_CASE("rig identify refuses a segment beyond the data instead of giving NaN", "[cli]") {
  const Result r = run_rig("identify " + flight_csv() + " --hover 500:600");
  CHECK(r.exit_code != 0);
  CHECK(r.err.find("segment 500:600 s lies outside the data") != std::string::npos);
  CHECK(r.out.find("nan") == std::string::npos);
}

TEST_CASE("rig validate reports open-loop metrics of every state derivative", "[cli]") {
  const std::string model = ident::test::kConfigs + "models/nimble_lateral_set1.yaml";
  const Result r = run_rig("validate " + model + " " + flight_csv() + " --json -");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const YAML::Node j = YAML::Load(r.out);
  for (const char* out : {"p_dot", "v_dot", "phi_dot"}) {
    INFO(out);
    CHECK(j["metrics"][out]["r2"].as<double>() > 0.99);
    CHECK(j["whiteness"][out]);
  }
  const Result text = run_rig("validate " + model + " " + flight_csv());
  REQUIRE(text.exit_code == 0);
  CHECK(text.out.find("phi_dot") != std::string::npos);
}

TEST_CASE("rig identify --plots draws PNGs with gnuplot, or names the package when it is missing", "[cli]") {
  const fs::path plots = work_dir() / "plots";
  INFO("gnuplot is not on the PATH: install the Debian package gnuplot-nox (scripts/setup.sh does)");
  REQUIRE(std::system("command -v gnuplot >/dev/null 2>&1") == 0);
  {
    const Result r = run_rig("identify " + flight_csv() + " --plots " + plots.string());
    INFO(r.err);
    REQUIRE(r.exit_code == 0);
    for (const char* png : {"derivatives.png", "autocorrelation.png", "psd.png", "eigenvalues.png"}) {
      INFO(png);
      const std::string bytes = slurp((plots / png).string());
      REQUIRE(bytes.size() > 1000);
      CHECK(bytes.substr(1, 3) == "PNG");
    }
    // The eigenvalue legend sits below the axes (its cross would read as a pole inside them).
    CHECK(slurp((plots / "eigenvalues.gp").string()).find("set key outside below") != std::string::npos);
    CHECK(slurp((plots / "derivatives.gp").string()).find("'estimated'") != std::string::npos);
    const Result v = run_rig("validate " + ident::test::kConfigs + "models/nimble_lateral_set1.yaml " + flight_csv() +
                             " --plots " + (plots / "validate").string());
    REQUIRE(v.exit_code == 0);
    CHECK(fs::exists(plots / "validate" / "derivatives.png"));
    // A model under validation predicts, as the text says; it estimates nothing.
    const std::string gp = slurp((plots / "validate" / "derivatives.gp").string());
    CHECK(gp.find("'predicted'") != std::string::npos);
    CHECK(gp.find("estimated") == std::string::npos);
    // No empty files are left beside the plots (gnuplot's output is kept only when it said something).
    for (const auto& e : fs::recursive_directory_iterator(plots)) {
      INFO(e.path().string());
      if (e.is_regular_file()) CHECK(fs::file_size(e.path()) > 0);
    }
  }
  const Result missing = run_rig("identify " + flight_csv() + " --plots " + plots.string(), "PATH=/nonexistent");
  CHECK(missing.exit_code == 2);
  CHECK(missing.err.find("gnuplot-nox") != std::string::npos);
}

TEST_CASE("rig validate --closed-loop --plots draws the closed-loop time histories", "[cli]") {
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    FAIL("gnuplot is not on the PATH: install the Debian package gnuplot-nox (the plots need it)");
  }
  const fs::path plots = work_dir() / "closed_loop_plots";
  fs::remove_all(plots);
  const std::string json = (work_dir() / "closed_loop.json").string();
  const Result r = run_rig("validate " + ident::test::kConfigs + "models/nimble_lateral_set1.yaml " + flight_csv() +
                           " --closed-loop --plots " + plots.string() + " --json " + json);
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  const fs::path png = plots / "closed_loop.png";
  CHECK(r.out.find("plot " + png.string()) != std::string::npos);
  const YAML::Node j = YAML::LoadFile(json);
  REQUIRE(j["plots"].size() == 2);
  CHECK(j["plots"][0].as<std::string>() == png.string());
  // The residual autocorrelation of the four simulated signals (thesis Figs C.4-C.9).
  CHECK(j["plots"][1].as<std::string>() == (plots / "autocorrelation.png").string());
  const std::string autocorrelation = slurp((plots / "autocorrelation.gp").string());
  for (const char* signal : {"residual of p:", "residual of phi:", "residual of v:", "residual of delta_f:"}) {
    CHECK(autocorrelation.find(signal) != std::string::npos);
  }
  // A real PNG of a 1400 x 1200 four-panel figure, not an empty or error image.
  const std::string bytes = slurp(png.string());
  REQUIRE(bytes.size() > 30000);
  CHECK(bytes.substr(0, 8) == std::string("\x89PNG\r\n\x1a\n", 8));
  // IHDR: width and height, big-endian, at bytes 16 and 20.
  const auto be32 = [&](std::size_t at) {
    return (static_cast<unsigned>(static_cast<unsigned char>(bytes[at])) << 24) |
           (static_cast<unsigned>(static_cast<unsigned char>(bytes[at + 1])) << 16) |
           (static_cast<unsigned>(static_cast<unsigned char>(bytes[at + 2])) << 8) |
           static_cast<unsigned>(static_cast<unsigned char>(bytes[at + 3]));
  };
  CHECK(bytes.substr(12, 4) == "IHDR");
  CHECK(be32(16) == 1400u);
  CHECK(be32(20) == 1200u);
  // The data behind it: time plus measured and simulated p, phi, phi_sp, v, delta_f, one row per sample.
  std::ifstream dat(plots / "closed_loop.dat");
  std::string header, line;
  std::getline(dat, header);
  for (const char* column :
       {" t_s ", " p:measured ", " p:simulated ", " phi:measured ", " phi:simulated ", " phi:phi_sp ", " phi:phi_ref ",
        " v:measured ", " v:simulated ", " delta_f:measured ", " delta_f:simulated "}) {
    INFO(column);
    CHECK((header + " ").find(column) != std::string::npos);
  }
  long rows = 0;
  std::size_t columns = 0;
  while (std::getline(dat, line)) {
    if (rows++ == 0) {
      std::istringstream in(line);
      double x = 0.0;
      while (in >> x) ++columns;
    }
  }
  CHECK(rows == j["samples"].as<long>());
  CHECK(columns == 11);
  const std::string script = slurp((plots / "closed_loop.gp").string());
  for (const char* panel : {"p ", "phi ", "v ", "delta_f "})
    CHECK(script.find(std::string("set title '") + panel) != std::string::npos);

  const Result missing = run_rig("validate " + ident::test::kConfigs + "models/nimble_lateral_set1.yaml " +
                                     flight_csv() + " --closed-loop --plots " + plots.string(),
                                 "PATH=/nonexistent");
  CHECK(missing.exit_code == 2);
  CHECK(missing.err.find("gnuplot-nox") != std::string::npos);
}

TEST_CASE("rig identify errors name the file, row and column, with exit code 2", "[cli]") {
  const fs::path dir = work_dir();
  SECTION("bad cell") {
    const fs::path bad = dir / "bad.csv";
    std::ofstream(bad) << "# a comment\nt,p,v,phi,delta_f,delta_t\n0,0,0,0,0,0\n0.1,0,zero,0,0,0\n";
    const Result r = run_rig("identify " + bad.string());
    CHECK(r.exit_code == 2);
    CHECK(r.out.empty());
    CHECK(r.err.find("bad.csv:4: row 2, column 'v': value 'zero' is not a number") != std::string::npos);
  }
  SECTION("unknown column") {
    const fs::path bad = dir / "unknown.csv";
    std::ofstream(bad) << "t,p,v,phi,delta_f,delta_t,gyro_x\n0,0,0,0,0,0,0\n0.1,0,0,0,0,0,0\n";
    const Result r = run_rig("identify " + bad.string());
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("unknown column gyro_x") != std::string::npos);
  }
  SECTION("too few samples") {
    const fs::path few = dir / "few.csv";
    std::ofstream(few) << "t,p,v,phi,delta_f,delta_t\n0,0,0,0,0,0\n0.1,1,0,0,0,0\n0.2,0,1,0,0,0\n";
    const Result r = run_rig("identify " + few.string());
    CHECK(r.exit_code == 2);
    CHECK(r.err.find("too few") != std::string::npos);
  }
  SECTION("usage") {
    CHECK(run_rig("identify").exit_code == 2);
    CHECK(run_rig("identify " + flight_csv() + " --bogus").exit_code == 2);
    CHECK(run_rig("identify " + flight_csv() + " --structure longitudinal").exit_code == 2);
    CHECK(run_rig("identify " + flight_csv() + " --method mle").exit_code == 2);
    CHECK(run_rig("identify " + flight_csv() + " --order ten").exit_code == 2);
    const Result spline = run_rig("identify " + flight_csv() + " --interpolation spline");
    CHECK(spline.exit_code == 2);
    CHECK(spline.err.find("--interpolation: spline not in {cubic,linear}") != std::string::npos);
    const Result nyquist = run_rig("identify " + flight_csv() + " --rate 16");
    CHECK(nyquist.exit_code == 2);
    CHECK(nyquist.err.find("cut-off") != std::string::npos);
    CHECK(run_rig("identify /nonexistent/flight.csv").exit_code == 2);
    CHECK(run_rig("validate " + flight_csv()).exit_code == 2);
    CHECK(run_rig("identify --help").exit_code == 0);
  }
}

TEST_CASE("rig discrepancy: text, JSON with the fixed keys, augmented model and report with plots", "[cli][heavy]") {
  const fs::path dir = work_dir() / "discrepancy";
  fs::create_directories(dir);
  const DerivativeModel set1 = ident::test::set1_model();
  const Vehicle vehicle = load_vehicle(set1.vehicle_file);
  ident::test::HiddenEffects hidden;
  hidden.on = {"kinematic_coupling"};
  ident::test::draw_magnitudes(hidden, 3);
  ident::test::GeneratorOptions o;
  o.seed = 3;
  const std::string csv = (dir / "flight.csv").string();
  write_flight_csv(ident::test::generate_flight(set1, vehicle, hidden, o), csv);
  const std::string json = (dir / "d.json").string(), model = (dir / "augmented.yaml").string();
  const std::string report = (dir / "report").string();
  const Result r = run_rig("discrepancy " + csv + " --model " + std::string(RIG_SOURCE_DIR) +
                           "/rig_configs/models/nimble_lateral_set1.yaml --json " + json + " --model-out " + model +
                           " --report " + report);
  INFO(r.out << r.err);
  REQUIRE(r.exit_code == 0);
  for (const char* part : {"verdict: effects", "kinematic_coupling", "gap on held-out data", "candidates", "located",
                           "model written to", "report written to"}) {
    INFO(part);
    CHECK(r.out.find(part) != std::string::npos);
  }
  const YAML::Node j = YAML::LoadFile(json);
  CHECK(j["verdict"].as<std::string>() == "effects");
  REQUIRE(j["effects"].size() == 1);
  CHECK(j["effects"][0]["name"].as<std::string>() == "kinematic_coupling");
  CHECK(j["effects"][0]["parameters"]["Y_pw"].as<double>() > 0.0);
  CHECK(j["effects"][0]["sigma"]["Y_pw"].as<double>() > 0.0);
  CHECK(j["candidates"].size() >= 6);
  for (const auto& c : j["candidates"]) CHECK_FALSE(c["reason"].as<std::string>().empty());
  CHECK(j["located"]["time"].IsSequence());
  CHECK(j["located"]["frequency"].IsSequence());
  CHECK(j["located"]["state"].IsSequence());
  CHECK_FALSE(j["gap"]["metric"].as<std::string>().empty());
  CHECK(j["gap"]["after"].as<double>() < j["gap"]["before"].as<double>());
  CHECK(j["gap"]["outputs"].size() == 2);
  // The gap where the effect lives, beside the identification band; the alarm rule.
  REQUIRE(j["gap"]["bands"].size() >= 2);
  CHECK(j["gap"]["bands"][0]["name"].as<std::string>() == "identification band");
  CHECK(j["gap"]["bands"][1]["name"].as<std::string>() == "kinematic_coupling");
  CHECK(j["gap"]["bands"][1]["after"].as<double>() < 0.8 * j["gap"]["bands"][1]["before"].as<double>());
  CHECK(j["alarm_rule"]["family_wise"].as<double>() < 0.01);
  CHECK(j["located"]["excitation"].size() == 2);
  CHECK(j["flights"].size() == 0);
  CHECK(r.out.find("gap by band") != std::string::npos);
  CHECK(load_model(model).effects.count("kinematic_coupling") == 1);
  // Closed loop: the data has phi_sp, so both models are flown by the rig's controller copy
  // (the generator's own PD loop is another controller: the figures are only present here;
  // system.discrepancy on the effect-free identification train checks them on a rig flight).
  REQUIRE(j["closed_loop"]["outputs"].size() == 4);
  CHECK(r.out.find("closed loop (model flown by the controller copy") != std::string::npos);
  for (const char* file : {"report.md", "outputs.png", "residuals.png", "residual_psd.png"}) {
    INFO(file);
    CHECK(fs::file_size(fs::path(report) / file) > 1000);
  }
  CHECK(slurp(report + "/report.md").find("kinematic_coupling") != std::string::npos);

  // Several flights pooled: each listed with its own estimate, and whether they agree.
  o.seed = 4;
  const std::string csv2 = (dir / "flight2.csv").string(), pooled_json = (dir / "pooled.json").string();
  write_flight_csv(ident::test::generate_flight(set1, vehicle, hidden, o), csv2);
  const Result pooled = run_rig("discrepancy " + csv + " " + csv2 + " --model " + std::string(RIG_SOURCE_DIR) +
                                "/rig_configs/models/nimble_lateral_set1.yaml --json " + pooled_json);
  INFO(pooled.out << pooled.err);
  REQUIRE(pooled.exit_code == 0);
  CHECK(pooled.out.find("pooled flights") != std::string::npos);
  const YAML::Node pj = YAML::LoadFile(pooled_json);
  REQUIRE(pj["flights"].size() == 2);
  CHECK(pj["flights"][1]["source"].as<std::string>().find("flight2.csv") != std::string::npos);
  CHECK(pj["flights"][0]["parameters"]["Y_pw"].as<double>() > 0.0);
  REQUIRE(pj["consistency"].size() == 1);
  CHECK(pj["consistency"][0]["effect"].as<std::string>() == "kinematic_coupling");
  CHECK(pj["closed_loop"]["outputs"].size() == 0);

  // Bad usage: exit 2, naming what is wrong.
  const Result no_model = run_rig("discrepancy " + csv);
  CHECK(no_model.exit_code == 2);
  CHECK(no_model.err.find("--model is required") != std::string::npos);
  const Result bad = run_rig("discrepancy " + csv + " --model " + std::string(RIG_SOURCE_DIR) +
                             "/rig_configs/models/nimble_lateral_set1.yaml --candidates warp_drive");
  CHECK(bad.exit_code != 0);
  CHECK(bad.err.find("unknown candidate 'warp_drive'") != std::string::npos);
  const Result folds = run_rig("discrepancy " + csv + " --model x.yaml --folds 2");
  CHECK(folds.exit_code == 2);
  CHECK(folds.err.find("--folds") != std::string::npos);
}

namespace {

/// A short synthetic set-1 flight as CSV (doublets from 0.3 s); `diverge` makes p, v and phi grow
/// as exp(6 (t - 1.5)) from 1.5 s on, to millions of rad/s by the end, as a simulation gone
/// unstable. Returns the file and the time of the first sample whose |p| exceeds 50 rad/s.
std::pair<std::string, double> short_flight_csv(const std::string& name, double duration_s, bool diverge) {
  const SyntheticOptions o = ident::test::short_identification_flight(duration_s, 11);
  const DerivativeModel m = ident::test::set1_model();
  FlightData d = simulate_synthetic(m, load_vehicle(m.vehicle_file), o);
  double first_bad_s = -1.0;
  if (diverge) {
    for (const char* s : {"p", "v", "phi"}) {
      Channel& c = d.channels.at(s);
      for (std::size_t k = 0; k < c.values.size(); ++k) {
        if (c.t_s[k] > 1.5) c.values[k] *= std::exp(6.0 * (c.t_s[k] - 1.5)) * 1e3;
        if (first_bad_s < 0.0 && std::string(s) == "p" && std::fabs(c.values[k]) > 50.0) first_bad_s = c.t_s[k];
      }
    }
  }
  const std::string file = (work_dir() / name).string();
  write_flight_csv(d, file);
  return {file, first_bad_s};
}

}  // namespace

TEST_CASE(
    "rig identify, validate and discrepancy refuse a diverged record with exit code 2, naming its first bad "
    "sample's time, column and bound",
    "[cli][bad_data]") {
  const auto [csv, t_bad] = short_flight_csv("diverged.csv", 4.0, true);
  REQUIRE(t_bad > 1.5);
  const std::string model = ident::test::kConfigs + "models/nimble_lateral_set1.yaml";
  char at[160];
  std::snprintf(at, sizeof at, " rad/s at t = %.4f s exceeds the physical bound 50 rad/s (vehicle file ", t_bad);
  for (const std::string& args :
       {"identify " + csv, "validate " + model + " " + csv, "validate " + model + " " + csv + " --closed-loop",
        "discrepancy " + csv + " --model " + model, "discrepancy " + flight_csv() + " " + csv + " --model " + model}) {
    const Result r = run_rig(args);
    INFO(args << "\n" << r.err);
    CHECK(r.exit_code == 2);
    CHECK(r.out.empty());
    CHECK(r.err.find(": error: refused: " + csv + ": p = ") != std::string::npos);
    CHECK(r.err.find(at) != std::string::npos);
    CHECK(r.err.find("rig_configs/vehicles/nimble_no_wifi.yaml, bound data_bounds.rate_max_radps)") !=
          std::string::npos);
  }
}

TEST_CASE(
    "rig identify completes on a 2.5 s record, the whiteness test skipped with a note saying how long a record "
    "it needs, in the text and the JSON",
    "[cli][bad_data]") {
  const std::string csv = short_flight_csv("short.csv", 2.5, false).first;
  const std::string note =
      "whiteness skipped: needs at least 2.79 s of data at this decimation (50 lags of 28 samples, 1429 samples at "
      "512 Hz), the record has 2.50 s";
  const std::string json = (work_dir() / "short.json").string();
  const Result r = run_rig("identify " + csv + " --w0 -0.30 --json " + json);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  CHECK(r.out.find("residual whiteness\n  " + note + "\n") != std::string::npos);
  CHECK(r.out.find("eigenvalues of the identified model") != std::string::npos);
  const YAML::Node j = YAML::LoadFile(json);
  CHECK(j["parameters"]["L_df"]["value"].as<double>() > 0.0);
  CHECK(j["notes"][0].as<std::string>() == note);
  CHECK(j["whiteness"]["p_dot"].IsNull());
  CHECK_FALSE(j["whiteness_detail"]["p_dot"]["tested"].as<bool>());
  CHECK(j["whiteness_detail"]["v_dot_star"]["note"].as<std::string>() == note);
}

TEST_CASE("a plant term flown in process is recovered by rig identify --terms and lowers rig validate's error",
          "[cli][terms]") {
  // The plant flies L += -2e-5 p^3 [N m] (plant.terms) through the identification doublet train;
  // the term model is set 1 with that expression at coefficient 0 (its value is what identify fits).
  const fs::path dir = work_dir();
  const std::string log = (dir / "terms.lcmlog").string();
  const double truth = -2.0e-5;
  const Result flight =
      run_rig("run " + ident::test::kConfigs + "id_doublet_train_fast.yaml --clock inprocess --seed 1 --log " + log +
              " --set 'plant.terms=[{equation: L, expression: \"p^3\", coefficient: -2.0e-5}]'");
  INFO(flight.out << flight.err);
  REQUIRE(flight.exit_code == 0);

  const std::string set1 = slurp(ident::test::kConfigs + "models/nimble_lateral_set1.yaml");
  std::string base = set1;
  base.replace(base.find("vehicle: ../vehicles/nimble_no_wifi.yaml"),
               std::string("vehicle: ../vehicles/nimble_no_wifi.yaml").size(),
               "vehicle: " + ident::test::kConfigs + "vehicles/nimble_no_wifi.yaml");
  const std::string with_term = (dir / "set1_p3.yaml").string();
  std::ofstream(with_term) << base << "terms:\n  - {equation: L, expression: \"p^3\", coefficient: 0}\n";

  const std::string json = (dir / "terms_ident.json").string(), fitted = (dir / "fitted.yaml").string();
  const Result id =
      run_rig("identify " + log + " --w0 -0.30 --terms " + with_term + " --json " + json + " --model-out " + fitted);
  INFO(id.out << id.err);
  REQUIRE(id.exit_code == 0);
  CHECK(id.out.find("L:p^3") != std::string::npos);
  const YAML::Node j = YAML::LoadFile(json);
  REQUIRE(j["parameters"]["L:p^3"]);
  const double value = j["parameters"]["L:p^3"]["value"].as<double>();
  const double sigma = j["parameters"]["L:p^3"]["sigma_coloured"].as<double>();
  INFO("L:p^3 = " << value << " sigma_c " << sigma);
  CHECK(std::fabs(value - truth) <= 3.0 * sigma);
  CHECK(sigma < 0.2 * std::fabs(truth));
  const DerivativeModel back = load_model(fitted);
  REQUIRE(back.terms.size() == 1);
  CHECK(back.terms[0].coefficient == Approx(value).epsilon(1e-8));

  // rig validate: the fitted model with its term predicts p_dot better than the same model without it.
  std::string text = slurp(fitted);
  const auto from = text.find("# generic terms"), to = text.find("\npublished:") + 1;
  REQUIRE(from != std::string::npos);
  REQUIRE(to > from);
  text.erase(from, to - from);
  const std::string without = (dir / "fitted_without.yaml").string();
  std::ofstream(without) << text;
  const Result v_with = run_rig("validate " + fitted + " " + log + " --json -");
  const Result v_without = run_rig("validate " + without + " " + log + " --json -");
  INFO(v_with.err << v_without.err);
  REQUIRE(v_with.exit_code == 0);
  REQUIRE(v_without.exit_code == 0);
  const double rmse_with = YAML::Load(v_with.out)["metrics"]["p_dot"]["rmse"].as<double>();
  const double rmse_without = YAML::Load(v_without.out)["metrics"]["p_dot"]["rmse"].as<double>();
  INFO("p_dot RMSE with the term " << rmse_with << ", without " << rmse_without);
  CHECK(rmse_with < rmse_without);
  // Closed loop (the model flown by the controller copy on the logged set-points) flies the term too.
  const Result cl_with = run_rig("validate " + fitted + " " + log + " --closed-loop --json -");
  const Result cl_without = run_rig("validate " + without + " " + log + " --closed-loop --json -");
  REQUIRE(cl_with.exit_code == 0);
  REQUIRE(cl_without.exit_code == 0);
  const double cl_rmse_with = YAML::Load(cl_with.out)["closed_loop"]["p"]["rmse"].as<double>();
  const double cl_rmse_without = YAML::Load(cl_without.out)["closed_loop"]["p"]["rmse"].as<double>();
  INFO("closed-loop p RMSE with the term " << cl_rmse_with << ", without " << cl_rmse_without);
  CHECK(cl_rmse_with < cl_rmse_without);

  // rig discrepancy takes the model's term as part of the model: refit in the baseline, written back.
  const std::string augmented = (dir / "augmented.yaml").string();
  const Result d = run_rig("discrepancy " + log + " --model " + with_term + " --model-out " + augmented + " --json -");
  INFO(d.err);
  REQUIRE(d.exit_code == 0);
  const YAML::Node dj = YAML::Load(d.out);
  REQUIRE(dj["baseline"]["L:p^3"]);
  const double refit = dj["baseline"]["L:p^3"]["value"].as<double>();
  CHECK(std::fabs(refit - truth) <= 3.0 * dj["baseline"]["L:p^3"]["sigma_coloured"].as<double>());
  const DerivativeModel aug = load_model(augmented);
  REQUIRE(aug.terms.size() == 1);
  CHECK(aug.terms[0].coefficient == Approx(dj["augmented"]["L:p^3"]["value"].as<double>()).epsilon(1e-8));

  // A model whose term does not parse is refused naming the file, the line and the key.
  const std::string bad = (dir / "bad_term.yaml").string();
  std::ofstream(bad) << base << "terms:\n  - {equation: L, expression: \"p^\", coefficient: 0}\n";
  const Result refused = run_rig("identify " + log + " --terms " + bad);
  CHECK(refused.exit_code == 2);
  CHECK_THAT(refused.err, Catch::Contains(bad + ":") && Catch::Contains("key 'terms[0].expression'") &&
                              Catch::Contains("does not parse: at position 3: expected an integer power"));
}
