// Unit tests of the plant's lateral gust: the Gauss-Markov default unchanged, the Dryden
// option's spectrum, variance and exact discretisation, and the config keys.

#include <cmath>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "core/model.h"
#include "effects/lateral_gust.h"
#include "plant/plant_model.h"
#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_estimates.h"
#include "turbulence/uncertainty.h"

using namespace nimble;
using nimble::effects::GustForm;
using nimble::plant::PlantConfig;
using nimble::plant::PlantModel;
namespace tb = nimble::turbulence;

namespace {

const std::string kModels = std::string(RIG_SOURCE_DIR) + "/rig_configs/models/";

struct Fixture {
  DerivativeModel model = load_model(kModels + "nimble_lateral_set1.yaml");
  Vehicle vehicle = load_vehicle(model.vehicle_file);
};

PlantConfig dryden_config(double sigma, double T, double rate_hz, std::uint64_t seed) {
  PlantConfig cfg;
  cfg.rate_hz = rate_hz;
  cfg.truth_rate_hz = rate_hz;
  cfg.feedback_rate_hz = rate_hz;
  cfg.effects.get<effects::LateralGustConfig>().enabled = true;
  cfg.effects.get<effects::LateralGustConfig>().form = GustForm::kDryden;
  cfg.effects.get<effects::LateralGustConfig>().sigma_mps = sigma;
  cfg.effects.get<effects::LateralGustConfig>().time_scale_s = T;
  cfg.seed = seed;
  return cfg;
}

/// The gust of `steps` plant steps at trim (the first sample is the initial state).
Eigen::VectorXd gust_record(const Fixture& f, const PlantConfig& cfg, std::size_t steps) {
  PlantModel plant(f.model, std::nullopt, f.vehicle, cfg);
  Eigen::VectorXd g(static_cast<Eigen::Index>(steps));
  g[0] = plant.truth().gust_v_mps;
  for (Eigen::Index k = 1; k < g.size(); ++k) {
    plant.step(plant.trim_command());
    g[k] = plant.truth().gust_v_mps;
  }
  return g;
}

ConfigMap gust_yaml(const std::string& body) {
  return ConfigMap::load_string("effects:\n  lateral_gust: {" + body + "}\n", "scenario.yaml");
}

}  // namespace

TEST_CASE("lateral gust: the Gauss-Markov default flies the same seeded values as before", "[plant][gust]") {
  // Values of the first-order Gauss-Markov gust before the Dryden option existed (seed 7,
  // sigma 0.2 m/s, tau 0.05 s, set 1 at trim, 1 kHz): gust and side velocity after n steps.
  Fixture f;
  PlantConfig cfg;
  cfg.effects.get<effects::LateralGustConfig>().enabled = true;
  cfg.effects.get<effects::LateralGustConfig>().sigma_mps = 0.2;
  cfg.effects.get<effects::LateralGustConfig>().tau_s = 0.05;
  cfg.seed = 7;
  REQUIRE(cfg.effects.get<effects::LateralGustConfig>().form == GustForm::kGaussMarkov);
  struct Golden {
    int step;
    double gust, v;
  };
  const std::vector<Golden> golden = {{1, 0.034561620216973551, 0.0},
                                      {2, -0.0046394581810847296, 6.7337233497671145e-05},
                                      {10, 0.00040095383709640164, 4.7319036269654312e-05},
                                      {1000, 0.46690967788667964, -0.13401538476081939},
                                      {3000, 0.050356342279317449, -0.028535452817405056}};
  PlantModel plant(f.model, std::nullopt, f.vehicle, cfg);
  CHECK(plant.truth().gust_v_mps == 0.0);  // Gauss-Markov starts at 0
  std::size_t next = 0;
  for (int i = 1; i <= 3000; ++i) {
    plant.step(plant.trim_command());
    if (next < golden.size() && golden[next].step == i) {
      INFO("step " << i);
      CHECK(plant.truth().gust_v_mps == Approx(golden[next].gust).epsilon(1e-12).margin(1e-15));
      CHECK(plant.truth().velocity_body_mps.y() == Approx(golden[next].v).epsilon(1e-9).margin(1e-15));
      ++next;
    }
  }
  CHECK(next == golden.size());
}

TEST_CASE("plant config: lateral_gust form dryden with its time scale, bad values name the key", "[plant][gust]") {
  const auto load = [](const std::string& body) {
    ConfigMap m = gust_yaml(body);
    return nimble::plant::plant_config_from(m);
  };
  const PlantConfig d = load("enabled: true, form: dryden, sigma_mps: 0.3, time_scale_s: 2.5");
  CHECK(d.effects.get<effects::LateralGustConfig>().form == GustForm::kDryden);
  CHECK(d.effects.get<effects::LateralGustConfig>().sigma_mps == 0.3);
  CHECK(d.effects.get<effects::LateralGustConfig>().time_scale_s == 2.5);
  CHECK(load("enabled: true, sigma_mps: 0.3").effects.get<effects::LateralGustConfig>().form == GustForm::kGaussMarkov);
  CHECK(load("enabled: true, form: gauss_markov").effects.get<effects::LateralGustConfig>().form ==
        GustForm::kGaussMarkov);
  CHECK(PlantConfig{}.effects.get<effects::LateralGustConfig>().time_scale_s == 1.0);
  CHECK(nimble::effects::to_string(GustForm::kDryden) == "dryden");

  CHECK_THROWS_WITH(load("enabled: true, form: dryden, sigma_mps: -0.1"),
                    Catch::Contains("effects.lateral_gust.sigma_mps"));
  CHECK_THROWS_WITH(load("enabled: true, form: dryden, time_scale_s: 0"),
                    Catch::Contains("effects.lateral_gust.time_scale_s"));
  CHECK_THROWS_WITH(load("enabled: true, form: dryden, time_scale_s: -1"),
                    Catch::Contains("effects.lateral_gust.time_scale_s"));
  CHECK_THROWS_WITH(load("enabled: true, form: von_karman"), Catch::Contains("effects.lateral_gust.form"));
  CHECK_THROWS_WITH(load("enabled: true, form: dryden, length_scale_m: 3"),
                    Catch::Contains("effects.lateral_gust.length_scale_m"));
}

TEST_CASE("plant file: the lateral_gust keys and their defaults", "[plant][gust]") {
  ConfigMap m = ConfigMap::load_file(std::string(RIG_SOURCE_DIR) + "/rig_configs/plant/nimble_plant.yaml");
  const PlantConfig c = nimble::plant::plant_config_from(m);
  const PlantConfig defaults;
  CHECK(c.effects.get<effects::LateralGustConfig>().form == defaults.effects.get<effects::LateralGustConfig>().form);
  CHECK(c.effects.get<effects::LateralGustConfig>().time_scale_s ==
        defaults.effects.get<effects::LateralGustConfig>().time_scale_s);
  // The defaults: the Dryden form's integral time scale T/2 equals the Gauss-Markov tau, so
  // both forms have the same S(0) = 2 sigma^2 tau = sigma^2 T.
  CHECK(c.effects.get<effects::LateralGustConfig>().time_scale_s ==
        Approx(2.0 * c.effects.get<effects::LateralGustConfig>().tau_s));
}

TEST_CASE("Dryden gust: the exact discrete variance is sigma^2 at the plant rate and at a coarse rate",
          "[plant][gust]") {
  const double sigma = 0.1, T = 1.0;
  const tb::ShapingFilter f = tb::time_based_second_order(sigma, T);
  const Eigen::VectorXd W = Eigen::VectorXd::Ones(1);
  for (const double dt : {1e-3, 1e-2, 0.5}) {
    INFO("dt " << dt);
    const tb::DiscreteModel d = tb::discretise(f.system, W, dt);
    const Eigen::MatrixXd P = tb::solve_discrete_lyapunov(d.Phi, d.Qd);
    CHECK((f.system.C * P * f.system.C.transpose())(0, 0) == Approx(sigma * sigma).epsilon(1e-9));
    // Euler (Phi = I + A dt, process noise B B' dt), the defect of common implementations,
    // inflates it by O(dt / T).
    const Eigen::MatrixXd Phi_e = Eigen::MatrixXd::Identity(2, 2) + f.system.A * dt;
    if (dt < 0.5) {
      const Eigen::MatrixXd P_e = tb::solve_discrete_lyapunov(Phi_e, f.system.B * f.system.B.transpose() * dt);
      const double inflation = (f.system.C * P_e * f.system.C.transpose())(0, 0) / (sigma * sigma) - 1.0;
      CHECK(inflation > 0.2 * dt / T);
    }
  }
  // The plant flies it at its rate: a long record at 100 Hz (the slowest plant rate) has
  // variance sigma^2 within its uncertainty.
  Fixture fx;
  const double rate = 100.0;
  const std::size_t N = 200000;  // 2000 s
  const Eigen::VectorXd g = gust_record(fx, dryden_config(sigma, T, rate, 5), N);
  const double s2 = tb::sample_variance(g);
  const double sd = tb::sample_variance_std_from_psd(f.psd, static_cast<double>(N) / rate);
  INFO("100 Hz: variance " << s2 << " against " << sigma * sigma << " +- " << sd);
  CHECK(std::fabs(s2 - sigma * sigma) < 3.0 * sd);
}

TEST_CASE("Dryden gust: seeded record with the analytical Welch PSD and variance sigma^2", "[plant][gust]") {
  Fixture fx;
  const double sigma = 0.1, T = 1.0, rate = 1000.0, dt = 1.0 / rate;
  const std::size_t N = 600000;  // 600 s at the plant rate
  const tb::ShapingFilter f = tb::time_based_second_order(sigma, T);
  for (const std::uint64_t seed : {3u, 4u}) {
    INFO("seed " << seed);
    const Eigen::VectorXd g = gust_record(fx, dryden_config(sigma, T, rate, seed), N);
    // Deterministic per seed; another seed another record.
    CHECK(gust_record(fx, dryden_config(sigma, T, rate, seed), 100) == g.head(100));
    CHECK(gust_record(fx, dryden_config(sigma, T, rate, seed + 10), 100) != g.head(100));
    // Stationary from the first sample: the first second has no start-up (not all ~0).
    CHECK(g.head(1000).cwiseAbs().maxCoeff() > 1e-3);

    // Variance within its uncertainty (uncertainty.h) of sigma^2.
    const double s2 = tb::sample_variance(g);
    const double sd = tb::sample_variance_std_from_psd(f.psd, static_cast<double>(N) * dt);
    INFO("variance " << s2 << " against " << sigma * sigma << " +- " << sd);
    CHECK(std::fabs(s2 - sigma * sigma) < 3.0 * sd);

    // Welch PSD inside the 95 % band of the analytical PSD: of every other bin (nearly
    // independent for the Hann window) from bin 2 to 20 rad/s, at most the binomial 0.999
    // quantile outside.
    const tb::SpectralEstimate e = tb::welch(g, dt, 1u << 15);
    const tb::ConfidenceBand band = tb::psd_confidence_band(e.dof, 0.95);
    std::size_t counted = 0, outside = 0;
    for (Eigen::Index k = 2; e.omega_radps[k] <= 20.0; k += 2) {
      const double r = e.psd[k] / f.psd(e.omega_radps[k]);
      ++counted;
      outside += (r < band.lower || r > band.upper) ? 1 : 0;
    }
    const std::size_t allowed = tb::binomial_upper_quantile(counted, 0.05, 0.999);
    INFO(counted << " bins (dof " << e.dof << "), outside the 95 % band " << outside << ", allowed " << allowed);
    CHECK(counted > 40);
    CHECK(outside <= allowed);
  }
}
