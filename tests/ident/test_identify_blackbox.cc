// The thesis's other identifications: the black-box structures (Eq 8.5 / 8.6, Appendix C.2) by
// equation error, where on a synthetic flight of set 1 (whose A and B a three-state black box
// contains) every entry comes back within its own coloured-residual sigma of set 1's; and OLS
// beside WLS (Appendix D); a three-state black box validated in closed loop.

#include <cmath>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "controller/attitude_controller.h"
#include "core/model.h"
#include "ident/closed_loop.h"
#include "ident/identify.h"
#include "ident/model_writer.h"
#include "ident/report.h"
#include "ident/synthetic.h"
#include "synthetic_flight.h"
#include "tests/support/blackbox_model.h"
#include "tests/support/scratch.h"

using namespace nimble;
using namespace nimble::ident;
using nimble::ident::test::identification_flight;
using nimble::ident::test::set1_model;

TEST_CASE("blackbox3 from a synthetic set-1 flight: A and B entries within 4 sigma of set 1's", "[identify]") {
  const DerivativeModel truth = set1_model();
  const Vehicle vehicle = load_vehicle(truth.vehicle_file);
  const StateSpace true_ss = build_state_space(truth, vehicle);
  const FlightData data = simulate_synthetic(truth, vehicle, identification_flight(7));
  IdentOptions o;
  o.structure = Structure::kBlackbox3;
  o.trim = truth.trim;
  const IdentResult r = identify(data, vehicle, truth.vehicle_file, o);
  REQUIRE(r.fits.size() == 3);
  CHECK(r.fits[0].output == "p_dot");
  CHECK(r.fits[1].output == "v_dot");
  CHECK(r.fits[2].output == "phi_dot");
  CHECK(r.fits[2].unit == "rad/s");
  REQUIRE(r.parameter_order.size() == 3 * (3 + 2));
  const std::vector<std::string> states{"p", "v", "phi"}, inputs{"df", "dt"};
  for (std::size_t i = 0; i < 3; ++i) {
    for (std::size_t k = 0; k < 3 + 2; ++k) {
      const std::string name = (k < 3 ? "a_" + states[i] + "_" + states[k] : "b_" + states[i] + "_" + inputs[k - 3]);
      const double want = k < 3 ? true_ss.A(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k))
                                : true_ss.B(static_cast<Eigen::Index>(i), static_cast<Eigen::Index>(k - 3));
      const ParameterEstimate& e = r.parameters.at(name);
      INFO(name << " = " << e.value << " +- " << e.sigma_coloured << ", set 1: " << want);
      CHECK(std::fabs(e.value - want) < 4.0 * e.sigma_coloured);
    }
  }
  // The kinematic row is found, to the filter's and the differentiator's precision.
  CHECK(r.parameters.at("a_phi_p").value == Approx(1.0).margin(0.01));
  // Its modes are set 1's.
  REQUIRE(r.eigenvalues.size() == 3);
  const auto want = sorted_eigenvalues(true_ss.A);
  for (std::size_t i = 0; i < 3; ++i) CHECK(std::abs(r.eigenvalues[i] - want[i]) < 0.1 * std::abs(want[i]));

  // Written as a model file and read back as a black box.
  const std::string file = nimble::test::scratch_file("test_ident_blackbox", "bb3.yaml");
  write_model_yaml(r.model, file, {"test"});
  const DerivativeModel back = load_model(file);
  CHECK(back.structure == Structure::kBlackbox3);
  CHECK(back.at("a_v_phi") == Approx(r.model.at("a_v_phi")).epsilon(1e-8));
  CHECK(back.trim.w0_mps == Approx(-0.30));
}

TEST_CASE("a black-box structure takes no term and no output error fit, and says why", "[identify]") {
  const DerivativeModel truth = set1_model();
  const Vehicle vehicle = load_vehicle(truth.vehicle_file);
  const FlightData data = simulate_synthetic(truth, vehicle, identification_flight(9));
  IdentOptions o;
  o.structure = Structure::kBlackbox3;
  o.terms.push_back(Term{"L", TermExpression::parse("p^3"), 0.0, "test"});
  CHECK_THROWS_WITH(identify(data, vehicle, truth.vehicle_file, o),
                    Catch::Contains("structure blackbox3 has no equation 'L'"));
  o.terms.clear();
  o.method = Method::kOutputError;
  CHECK_THROWS_WITH(identify(data, vehicle, truth.vehicle_file, o), Catch::Contains("lateral3 structure only"));
}

TEST_CASE("OLS beside WLS (Appendix D): every parameter with both estimates, sigmas and relative sigmas",
          "[identify]") {
  const DerivativeModel truth = set1_model();
  const Vehicle vehicle = load_vehicle(truth.vehicle_file);
  const FlightData data = simulate_synthetic(truth, vehicle, identification_flight(11));
  IdentOptions o;
  o.trim = truth.trim;
  o.method = Method::kOls;
  const IdentResult ols = identify(data, vehicle, truth.vehicle_file, o);
  o.method = Method::kWls;
  const IdentResult wls = identify(data, vehicle, truth.vehicle_file, o);
  const std::string text = methods_comparison_text(ols, wls);
  const YAML::Node rows = YAML::Load(methods_comparison_json(ols, wls));
  REQUIRE(rows.size() == ols.parameter_order.size());
  for (std::size_t i = 0; i < ols.parameter_order.size(); ++i) {
    const std::string& name = ols.parameter_order[i];
    INFO(name);
    CHECK(text.find("\n  " + name + " ") != std::string::npos);
    CHECK(rows[i]["name"].as<std::string>() == name);
    CHECK(rows[i]["ols"]["value"].as<double>() == ols.parameters.at(name).value);
    CHECK(rows[i]["wls"]["sigma"].as<double>() == std::fabs(wls.parameters.at(name).sigma));
    CHECK(rows[i]["wls"]["rel_sigma_pct"].as<double>() ==
          Approx(100.0 * std::fabs(wls.parameters.at(name).sigma / wls.parameters.at(name).value)));
    // Two estimators of the same record: the same parameter, within their coloured spread.
    const double spread = ols.parameters.at(name).sigma_coloured + wls.parameters.at(name).sigma_coloured;
    CHECK(std::fabs(ols.parameters.at(name).value - wls.parameters.at(name).value) < 3.0 * spread);
  }
  CHECK_THROWS_WITH(methods_comparison_text(wls, ols), Catch::Contains("needs an OLS and a WLS identification"));
}

TEST_CASE("a three-state black box holding set 1's A and B validates in closed loop as set 1 does", "[identify]") {
  const DerivativeModel grey = set1_model();
  const Vehicle vehicle = load_vehicle(grey.vehicle_file);
  const StateSpace ss = build_state_space(grey, vehicle);
  const DerivativeModel box = nimble::test::blackbox_of(grey, ss);
  const FlightData data = simulate_synthetic(grey, vehicle, identification_flight(7));
  ClosedLoopOptions o;
  o.controller = load_controller_config(nimble::ident::test::kConfigs + "controller/nimble_attitude.yaml");
  const ClosedLoopResult a = validate_closed_loop(data, grey, vehicle, o);
  const ClosedLoopResult b = validate_closed_loop(data, box, vehicle, o);
  for (const char* s : {"p", "v", "phi", "delta_f"}) {
    INFO(s);
    CHECK(a.simulated.at(s).cwiseAbs().maxCoeff() >
          0.01);  // the loop flew (the synthetic flight's controller is not the copy's)
    CHECK(b.fits.at(s).r2 == Approx(a.fits.at(s).r2).margin(1e-9));
    CHECK((b.simulated.at(s) - a.simulated.at(s)).cwiseAbs().maxCoeff() < 1e-9);
  }
  // A four-state model has no place in the three-state loop: refused, naming its structure.
  DerivativeModel four = load_model(nimble::ident::test::kConfigs + "models/nimble_lateral4_yaw.yaml");
  CHECK_THROWS_WITH(
      validate_closed_loop(data, four, vehicle, o),
      Catch::Contains("needs a three-state model (lateral3 or blackbox3)") && Catch::Contains("is lateral4"));
}
