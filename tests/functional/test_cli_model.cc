// Functional tests of `rig model`: the real executable, its JSON and its errors.

#include <sys/wait.h>
#include <unistd.h>

#include <complex>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/run_rig.h"
#include "tests/support/scratch.h"

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

using nimble::test::run_rig;
using nimble::test::slurp;
using Result = nimble::test::RigResult;

}  // namespace

TEST_CASE("rig model --json gives a parseable object with A, B, states, inputs, eigenvalues", "[cli]") {
  const Result r = run_rig("model " + kConfigs + "models/nimble_lateral_set1.yaml --json");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.err.empty());
  // JSON is a subset of YAML 1.2 flow style: yaml-cpp parses it.
  const YAML::Node j = YAML::Load(r.out);
  REQUIRE(j.IsMap());
  REQUIRE(j["A"].IsSequence());
  REQUIRE(j["A"].size() == 3);
  for (const auto& row : j["A"]) CHECK(row.size() == 3);
  REQUIRE(j["B"].size() == 3);
  for (const auto& row : j["B"]) CHECK(row.size() == 2);
  CHECK(j["states"].as<std::vector<std::string>>() == std::vector<std::string>{"p", "v", "phi"});
  CHECK(j["inputs"].as<std::vector<std::string>>() == std::vector<std::string>{"delta_f", "delta_t"});
  REQUIRE(j["eigenvalues"].size() == 3);

  // Done-when check of the foundation: -5.18 and 0.32 +- 2.73i within 2 %.
  std::vector<std::complex<double>> eig;
  for (const auto& pair : j["eigenvalues"]) {
    REQUIRE(pair.size() == 2);
    eig.emplace_back(pair[0].as<double>(), pair[1].as<double>());
  }
  for (const std::complex<double> target : {std::complex<double>(-5.18, 0), {0.32, 2.73}, {0.32, -2.73}}) {
    double best = INFINITY;
    for (const auto& z : eig) best = std::min(best, std::abs(z - target));
    CHECK(best / std::abs(target) < 0.02);
  }
  REQUIRE(j["modes"].size() == 2);
  CHECK(j["modes"][1]["eigenvector_nondim"]["v"]["magnitude"].as<double>() == Approx(0.70).margin(0.02));
}

TEST_CASE("rig model text report has the matrices, modes and eigenvectors", "[cli]") {
  const Result r = run_rig("model " + kConfigs + "models/nimble_lateral_set2.yaml");
  REQUIRE(r.exit_code == 0);
  for (const char* part : {"\nA\n", "\nB\n", "eigenvalues", "modes", "UNSTABLE", "oscillatory",
                           "non-dimensional eigenvectors", "phi+", "published eigenvalues"}) {
    INFO(part);
    CHECK(r.out.find(part) != std::string::npos);
  }
}

TEST_CASE("rig model --vehicle overrides the model's vehicle", "[cli]") {
  const Result a = run_rig("model " + kConfigs + "models/nimble_lateral_set1.yaml --json");
  const Result b = run_rig("model " + kConfigs + "models/nimble_lateral_set1.yaml --json --vehicle " + kConfigs +
                           "vehicles/nimble_wifi.yaml");
  REQUIRE(a.exit_code == 0);
  REQUIRE(b.exit_code == 0);
  const YAML::Node ja = YAML::Load(a.out), jb = YAML::Load(b.out);
  CHECK(jb["vehicle"]["name"].as<std::string>() == "nimble_wifi");
  CHECK(ja["A"][1][1].as<double>() != jb["A"][1][1].as<double>());
}

TEST_CASE("rig model errors go to stderr with exit code 2", "[cli]") {
  SECTION("missing file") {
    const Result r = run_rig("model /nonexistent/model.yaml");
    CHECK(r.exit_code == 2);
    CHECK(r.out.empty());
    CHECK(r.err.find("/nonexistent/model.yaml") != std::string::npos);
    CHECK(r.err.find("file not found") != std::string::npos);
  }
  SECTION("config error names the key") {
    const std::string path = nimble::test::scratch_file("bad_model", "model.yaml");
    std::string text = slurp(kConfigs + "models/nimble_lateral_set1.yaml");
    text.replace(text.find("Lp: -2.43e-04"), 13, "Lp: minus_two");
    text.replace(text.find("../vehicles/"), 12, kConfigs + "vehicles/");
    std::ofstream(path) << text;
    const Result r = run_rig("model " + path + " --json");
    std::filesystem::remove(path);
    CHECK(r.exit_code == 2);
    CHECK(r.out.empty());
    CHECK(r.err.find("derivatives.Lp") != std::string::npos);
    CHECK(r.err.find("minus_two") != std::string::npos);
  }
  SECTION("bad usage") {
    CHECK(run_rig("model").exit_code == 2);
    CHECK(run_rig("model a.yaml --bogus").exit_code == 2);
    CHECK(run_rig("nonsense").exit_code == 2);
  }
}

TEST_CASE("rig model on a black-box model: A and B as written, and how far its phi-dot row is from kinematics",
          "[cli]") {
  // Set 1's A and B (from rig model itself) written as blackbox3, with a phi-dot row 2 % off.
  const Result grey = run_rig("model " + kConfigs + "models/nimble_lateral_set1.yaml --json");
  REQUIRE(grey.exit_code == 0);
  const YAML::Node g = YAML::Load(grey.out);
  const std::vector<std::string> states{"p", "v", "phi"}, inputs{"df", "dt"};
  const std::string file = nimble::test::scratch_file("cli_model", "bb3.yaml");
  std::ofstream out(file);
  out << "name: bb3\nsource: set 1 as a black box\nstructure: blackbox3\nvehicle: " << kConfigs
      << "vehicles/nimble_no_wifi.yaml\ninputs: [delta_f, delta_t]\n"
      << "trim: {u0_mps: 0.0, w0_mps: -0.30, theta0_rad: 0.0, phi0_rad: 0.0}\nderivatives:\n";
  out.precision(17);
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t k = 0; k < 3; ++k) {
      const double a = g["A"][i][k].as<double>() * (i == 2 && k == 0 ? 0.98 : 1.0);
      out << "  a_" << states[i] << "_" << states[k] << ": " << a << "\n";
    }
    for (std::size_t j = 0; j < 2; ++j)
      out << "  b_" << states[i] << "_" << inputs[j] << ": " << g["B"][i][j].as<double>() << "\n";
  }
  out.close();
  const Result r = run_rig("model " + file + " --json");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  const YAML::Node j = YAML::Load(r.out);
  CHECK(j["structure"].as<std::string>() == "blackbox3");
  for (std::size_t i = 0; i < 2; ++i) {
    for (std::size_t k = 0; k < 3; ++k) CHECK(j["A"][i][k].as<double>() == g["A"][i][k].as<double>());
  }
  CHECK(j["A"][2][0].as<double>() == Approx(0.98));
  CHECK(j["kinematic_row_difference"].as<double>() == Approx(0.02));
  CHECK_FALSE(g["kinematic_row_difference"]);  // a grey-box model has none
  const Result text = run_rig("model " + file);
  CHECK(text.out.find("its phi_dot row differs from the plant's kinematics") != std::string::npos);
}
