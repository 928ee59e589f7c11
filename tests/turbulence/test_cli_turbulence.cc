// Functional tests of `rig turbulence`: the real executable, its JSON keys, its report, its errors.

#include <unistd.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "../support/run_rig.h"
#include "tests/support/scratch.h"

namespace {

const std::string kPractical = std::string(RIG_SOURCE_DIR) + "/rig_configs/turbulence/ce500_practical.yaml";

using nimble::test::run_rig;
using Result = nimble::test::RigResult;

}  // namespace

TEST_CASE("rig turbulence --json - gives the fixed keys", "[cli][turbulence]") {
  const Result r = run_rig("turbulence " + kPractical + " --json - --duration 200 --seed 3");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  // JSON is a subset of YAML 1.2 flow style: yaml-cpp parses it.
  const YAML::Node j = YAML::Load(r.out);
  REQUIRE(j.IsMap());
  for (const char* system : {"uncontrolled", "controlled", "reduced"}) {
    INFO(system);
    const YAML::Node eig = j["systems"][system]["eigenvalues"];
    REQUIRE(eig.IsSequence());
    CHECK(eig.size() == 10);
    for (const auto& pair : eig) {
      REQUIRE(pair.size() == 2);
      CHECK(std::isfinite(pair[0].as<double>()));
    }
    CHECK(j["systems"][system]["max_distance"].as<double>() < 1e-3);
  }
  for (const char* system : {"controlled", "reduced"}) {
    for (const char* output : {"beta", "phi", "p_hat", "r_hat", "a_y"}) {
      const YAML::Node v = j["variances"][system][output];
      INFO(system << " " << output);
      REQUIRE(v.IsMap());
      const double lyapunov = v["lyapunov"].as<double>();
      CHECK(lyapunov > 0.0);
      for (const char* method : {"analytical_psd", "periodogram", "welch", "sample"}) {
        INFO(method);
        CHECK(v[method].as<double>() > 0.2 * lyapunov);
        CHECK(v[method].as<double>() < 5.0 * lyapunov);
      }
    }
  }
  CHECK(j["variances"]["controlled"]["beta"]["lyapunov"].as<double>() == Approx(2.2229).epsilon(1e-4));
  CHECK(j["options"]["dt_s"].as<double>() == 0.05);
  CHECK(j["options"]["samples"].as<long long>() == 4000);
  CHECK(j["table_5_1"].size() == 40);
}

TEST_CASE("rig turbulence prints Table 2.1 and Table 5.1 beside ours", "[cli][turbulence]") {
  const Result r = run_rig("turbulence " + kPractical + " --duration 100");
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find("Table 2.1") != std::string::npos);
  CHECK(r.out.find("Dutch roll") != std::string::npos);
  CHECK(r.out.find("spiral (unstable)") != std::string::npos);
  CHECK(r.out.find("Table 5.1") != std::string::npos);
  CHECK(r.out.find("lyapunov") != std::string::npos);
  CHECK(r.out.find("FAILED") == std::string::npos);
}

TEST_CASE("rig turbulence rejects bad usage and bad files with exit 2 and a message", "[cli][turbulence]") {
  const Result dt = run_rig("turbulence " + kPractical + " --dt -1");
  CHECK(dt.exit_code == 2);
  CHECK(dt.err.find("--dt") != std::string::npos);
  const Result missing = run_rig("turbulence /nonexistent/ce500.yaml");
  CHECK(missing.exit_code == 2);
  CHECK(missing.err.find("/nonexistent/ce500.yaml") != std::string::npos);
  const Result segment = run_rig("turbulence " + kPractical + " --welch-segment 100");
  CHECK(segment.exit_code == 2);
}

TEST_CASE("rig turbulence --plots writes PNGs, or says gnuplot is missing", "[cli][turbulence]") {
  const std::filesystem::path dir = nimble::test::scratch_path("turbulence_plots");
  // Without gnuplot on the PATH: a clear error, not a crash.
  const Result none =
      run_rig("turbulence " + kPractical + " --duration 100 --plots " + dir.string(), "PATH=/nonexistent");
  CHECK(none.exit_code == 2);
  CHECK(none.err.find("gnuplot-nox") != std::string::npos);
  if (std::system("command -v gnuplot >/dev/null 2>&1") != 0) {
    WARN("gnuplot not installed: the PNG half of this test is skipped");
    return;
  }
  const Result r = run_rig("turbulence " + kPractical + " --duration 100 --plots " + dir.string());
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  for (const char* png : {"psd_matrix.png", "time_histories.png", "pole_map.png"}) {
    INFO(png);
    CHECK(std::filesystem::file_size(dir / png) > 1000);
  }
  std::filesystem::remove_all(dir);
}
