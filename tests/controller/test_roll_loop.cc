// The roll loop as a sampled linear system (controller/roll_loop.h) and its margins
// (controller/loop_margins.h): the assembled loop steps as the attitude controller's own code
// does, the margins are where the closed loop's stability really changes, a sampled
// integrator's margins are the textbook's, and the design reaches what it states.

#include <algorithm>
#include <cmath>
#include <complex>
#include <deque>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>

#include "controller/attitude_controller.h"
#include "controller/loop_margins.h"
#include "controller/roll_loop.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "core/constants.h"

using namespace nimble;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

StateSpace lateral_set(int n) {
  const DerivativeModel m = load_model(kConfigs + "models/nimble_lateral_set" + std::to_string(n) + ".yaml");
  return build_state_space(m, load_vehicle(m.vehicle_file));
}

ControllerConfig shipped_controller() { return load_controller_config(kConfigs + "controller/nimble_attitude.yaml"); }

RollLoopConfig loop_of(const std::string& gains, double latency_s) {
  const ControllerConfig c = shipped_controller();
  RollLoopConfig r = roll_loop_config(c, roll_gain_set(c, gains));
  r.latency_s = latency_s;
  return r;
}

double spectral_radius(const Eigen::MatrixXd& m) { return m.eigenvalues().cwiseAbs().maxCoeff(); }

/// phi of the aircraft at each control step, flying the production AttitudeController on the
/// plant and flap actuator discretised at T / substeps, the command acting `latency_s` after
/// its step (a whole number of substeps), for a roll set-point step of `step_rad`.
std::vector<double> fly_controller(const StateSpace& lateral, const RollLoopConfig& cfg, double step_rad, int steps,
                                   int substeps) {
  ControllerConfig cc = shipped_controller();
  cc.roll_gain_sets = {{"test", cfg.gains}};
  cc.default_gain_set = "test";
  AttitudeController controller(cc);
  const StateSpace plant = roll_plant_with_actuator(lateral, cfg);
  const double T = 1.0 / cfg.rate_hz, h = T / substeps;
  const DiscreteStateSpace d = discretize_zoh(plant, h);
  const long lag = std::lround(cfg.latency_s / h);
  std::deque<double> pending(static_cast<std::size_t>(lag), 0.0);  // the command acting, per substep
  Eigen::VectorXd x = Eigen::VectorXd::Zero(4);
  std::vector<double> phi;
  double cmd = 0.0;
  for (int k = 0; k < steps; ++k) {
    phi.push_back(x(2));
    ControllerInput in;
    in.phi_rad = x(2);
    in.p_radps = x(0);
    in.roll_sp_rad = step_rad;
    cmd = controller.step(in).delta_f_cmd_radps;
    for (int j = 0; j < substeps; ++j) {
      pending.push_back(cmd);
      const double applied = pending.front();
      pending.pop_front();
      x = d.Ad * x + d.Bd * applied;
    }
  }
  return phi;
}

}  // namespace

TEST_CASE("roll loop: the assembled set-point loop steps as the attitude controller's code does", "[roll_loop]") {
  const StateSpace lat = lateral_set(1);
  const double T = 1.0 / 512.0;
  for (const double latency : {0.0, 2.0 * T, 0.4 * T, 3.7 * T}) {
    CAPTURE(latency);
    const RollLoopConfig cfg = loop_of("fast", latency);
    // 1 deg: the reference generator's rate and acceleration limits and the clip stay far away.
    const double step = 1.0 * kPi / 180.0;
    const int steps = 1024;
    const StepResponse r = roll_step_response(roll_setpoint_loop(lat, cfg), step, (steps - 1) * T);
    const std::vector<double> flown = fly_controller(lat, cfg, step, steps, 10);
    REQUIRE(r.phi_rad.size() == flown.size());
    double worst = 0.0, peak = 0.0;
    for (std::size_t k = 0; k < flown.size(); ++k) {
      worst = std::max(worst, std::abs(r.phi_rad[k] - flown[k]));
      peak = std::max(peak, std::abs(flown[k]));
    }
    CHECK(peak > 0.5 * step);
    CHECK(worst < 1e-9 * step / 1e-2);  // 1e-7 of the step: the same difference equations
  }
}

TEST_CASE("loop margins: a sampled integrator's margins are the textbook's", "[loop_margins]") {
  // L(z) = K T / (z - 1): closed-loop pole 1 - K T; unstable beyond K T = 2 (GM 2 / (K T) at the
  // Nyquist frequency); |L| = 1 where 2 sin(w T / 2) = K T, with PM = 90 deg - w T / 2.
  const double T = 0.01, K = 20.0;
  BrokenLoop loop;
  loop.A = Eigen::MatrixXd::Ones(1, 1);
  loop.B = Eigen::VectorXd::Constant(1, T);
  loop.C = Eigen::RowVectorXd::Constant(1, -K);
  loop.dt_s = T;
  const LoopMargins m = loop_margins(loop);
  REQUIRE(m.closed_loop_stable);
  CHECK_FALSE(m.open_loop_stable);  // the pole at z = 1 is not inside the circle
  CHECK(m.gain_margin == Approx(2.0 / (K * T)).epsilon(1e-6));
  CHECK(m.gain_margin_hz == Approx(0.5 / T).epsilon(1e-9));
  const double wc = 2.0 / T * std::asin(K * T / 2.0);
  CHECK(m.crossover_hz == Approx(wc / (2 * kPi)).epsilon(1e-6));
  const double pm = 90.0 - wc * T / 2.0 * 180.0 / kPi;
  CHECK(m.phase_margin_deg == Approx(pm).epsilon(1e-6));
  CHECK(m.delay_margin_s == Approx(pm * kPi / 180.0 / wc).epsilon(1e-6));
  CHECK(m.sensitivity_peak == Approx(2.0 / (2.0 - K * T)).epsilon(1e-6));
  CHECK(m.gain_reduction_margin == 0.0);  // any smaller gain is stable
}

TEST_CASE("roll loop: each margin is where the rig's closed loop loses its stability", "[roll_loop]") {
  const double T = 1.0 / 512.0;
  for (const char* gains : {"fast", "slow"}) {
    for (const double latency : {0.0, 2.0 * T}) {
      CAPTURE(gains, latency);
      const StateSpace lat = lateral_set(1);
      const RollLoopConfig cfg = loop_of(gains, latency);
      const BrokenLoop loop = roll_broken_loop(lat, cfg, LoopBreak::kActuator);
      const LoopMargins m = loop_margins(loop);
      REQUIRE(m.closed_loop_stable);
      CHECK_FALSE(m.open_loop_stable);  // the Nimble is unstable without its controller
      REQUIRE(std::isfinite(m.gain_margin));
      CHECK(schur_stable(closed_loop_matrix(loop, m.gain_margin * 0.999)));
      CHECK_FALSE(schur_stable(closed_loop_matrix(loop, m.gain_margin * 1.001)));
      // The unstable open loop needs a minimum gain.
      REQUIRE(m.gain_reduction_margin > 0.0);
      CHECK(schur_stable(closed_loop_matrix(loop, m.gain_reduction_margin * 1.001)));
      CHECK_FALSE(schur_stable(closed_loop_matrix(loop, m.gain_reduction_margin * 0.999)));
      // The delay margin on the exactly sampled loop with the extra latency (modified z-transform).
      RollLoopConfig late = cfg;
      late.latency_s = latency + 0.99 * m.delay_margin_s;
      CHECK(spectral_radius(closed_loop_matrix(roll_broken_loop(lat, late, LoopBreak::kActuator))) < 1.0);
      late.latency_s = latency + 1.01 * m.delay_margin_s;
      CHECK(spectral_radius(closed_loop_matrix(roll_broken_loop(lat, late, LoopBreak::kActuator))) > 1.0);
      // Sensitivity bounds every loop obeys (Skogestad & Postlethwaite Eq 2.40, 2.41).
      CHECK(m.gain_margin >= m.sensitivity_peak / (m.sensitivity_peak - 1.0) * (1 - 1e-9));
      CHECK(m.phase_margin_deg * kPi / 180.0 >= 2.0 * std::asin(0.5 / m.sensitivity_peak) * (1 - 1e-9));
    }
  }
}

TEST_CASE("roll loop: broken at the actuator or at either sensor, it is the same closed loop", "[roll_loop]") {
  const StateSpace lat = lateral_set(2);
  const RollLoopConfig cfg = loop_of("slow", 2.0 / 512.0);
  auto sorted_poles = [&](LoopBreak b) {
    const Eigen::VectorXcd e = closed_loop_matrix(roll_broken_loop(lat, cfg, b)).eigenvalues();
    std::vector<std::complex<double>> v(e.data(), e.data() + e.size());
    std::sort(v.begin(), v.end(),
              [](auto a, auto b) { return a.real() != b.real() ? a.real() < b.real() : a.imag() < b.imag(); });
    return v;
  };
  const auto actuator = sorted_poles(LoopBreak::kActuator);
  for (const LoopBreak b : {LoopBreak::kPhi, LoopBreak::kP}) {
    const auto other = sorted_poles(b);
    REQUIRE(other.size() == actuator.size());
    for (std::size_t i = 0; i < other.size(); ++i) CHECK(std::abs(other[i] - actuator[i]) < 1e-9);
  }
  // The margins differ with the break: the angle loop alone has its own.
  const LoopMargins at_phi = loop_margins(roll_broken_loop(lat, cfg, LoopBreak::kPhi));
  const LoopMargins at_actuator = loop_margins(roll_broken_loop(lat, cfg, LoopBreak::kActuator));
  CHECK(at_phi.closed_loop_stable);
  CHECK(std::abs(at_phi.gain_margin - at_actuator.gain_margin) > 1e-3);
}

TEST_CASE("roll loop: the shipped gains on the thesis's five model sets", "[roll_loop]") {
  // Both gain sets hold every set, on the truth and on the estimate; the slow set has the
  // larger margins on every one, and the estimate's latency takes margin from both.
  for (int set = 1; set <= 5; ++set) {
    const StateSpace lat = lateral_set(set);
    for (const double latency : {0.0, 2.0 / 512.0}) {
      CAPTURE(set, latency);
      const RollLoopAnalysis fast = analyse_roll_loop(lat, loop_of("fast", latency));
      const RollLoopAnalysis slow = analyse_roll_loop(lat, loop_of("slow", latency));
      REQUIRE(fast.margins.closed_loop_stable);
      REQUIRE(slow.margins.closed_loop_stable);
      CHECK(slow.margins.gain_margin > fast.margins.gain_margin);
      CHECK(slow.margins.phase_margin_deg > fast.margins.phase_margin_deg);
      CHECK(slow.margins.delay_margin_s > fast.margins.delay_margin_s);
      CHECK(fast.has_dominant_pair);
      CHECK(fast.dominant.damping < slow.dominant.damping);
      CHECK(fast.bandwidth_hz > 1.0);
      CHECK(fast.bandwidth_hz < 10.0);
    }
    const RollLoopAnalysis truth = analyse_roll_loop(lat, loop_of("fast", 0.0));
    const RollLoopAnalysis estimate = analyse_roll_loop(lat, loop_of("fast", 2.0 / 512.0));
    CHECK(estimate.margins.phase_margin_deg < truth.margins.phase_margin_deg);
    CHECK(estimate.margins.delay_margin_s == Approx(truth.margins.delay_margin_s - 2.0 / 512.0).margin(1e-3));
  }
}

TEST_CASE("roll loop: the step response settles where the tracking gain at 0 Hz says", "[roll_loop]") {
  const StateSpace lat = lateral_set(1);
  const RollLoopConfig cfg = loop_of("slow", 0.0);
  const RollLoopAnalysis a = analyse_roll_loop(lat, cfg);
  const StepResponse r = roll_step_response(roll_setpoint_loop(lat, cfg), 0.1, 20.0);
  CHECK(r.phi_rad.back() == Approx(0.1 * a.dc_gain).epsilon(1e-3));
  CHECK(r.phi_ref_rad.back() == Approx(0.1).epsilon(1e-6));  // the generator reaches its set-point
  CHECK(a.dc_gain > 0.5);
  CHECK(a.dc_gain < 1.0);  // a PD on a type-0 loop leaves a steady error
}

TEST_CASE("roll loop: a design reaches the margin it states, or says where one can", "[roll_loop]") {
  const StateSpace lat = lateral_set(1);
  const RollLoopConfig cfg = loop_of("fast", 2.0 / 512.0);
  const RollDesign d = design_roll_gains(lat, cfg, DesignRequest{45.0, 1.0});
  REQUIRE(d.feasible);
  CHECK(d.gains.kp_per_rad > 0.0);
  CHECK(d.gains.kd_per_radps > 0.0);
  CHECK(d.lowpass_cutoff_hz == 15.0);
  CHECK(d.analysis.margins.phase_margin_deg == Approx(45.0).margin(1e-3));
  CHECK(d.analysis.margins.crossover_hz == Approx(1.0).epsilon(1e-4));
  RollLoopConfig check = cfg;
  check.gains = d.gains;
  CHECK(loop_margins(roll_broken_loop(lat, check, LoopBreak::kActuator)).phase_margin_deg == Approx(45.0).margin(1e-3));

  const RollDesign none = design_roll_gains(lat, cfg, DesignRequest{60.0, 4.0});
  CHECK_FALSE(none.feasible);
  CHECK(none.note.find("no PD gains") != std::string::npos);
  const RollDesign elsewhere = design_roll_gains(lat, cfg, DesignRequest{45.0, 2.5});
  CHECK_FALSE(elsewhere.feasible);
  CHECK(elsewhere.note.find("reached at crossovers") != std::string::npos);

  CHECK_THROWS_WITH(design_roll_gains(lat, cfg, DesignRequest{95.0, 1.0}), Catch::Contains("phase_margin_deg"));
  CHECK_THROWS_WITH(design_roll_gains(lat, cfg, DesignRequest{45.0, 200.0}), Catch::Contains("crossover_hz"));
}

TEST_CASE("roll loop: bad input names the problem", "[roll_loop]") {
  const StateSpace lat = lateral_set(1);
  const DerivativeModel four = load_model(kConfigs + "models/nimble_lateral4_yaw.yaml");
  const StateSpace lat4 = build_state_space(four, load_vehicle(four.vehicle_file));
  CHECK_THROWS_WITH(roll_broken_loop(lat4, loop_of("fast", 0.0), LoopBreak::kActuator), Catch::Contains("lateral3"));
  RollLoopConfig cfg = loop_of("fast", 0.0);
  cfg.lowpass_cutoff_hz = 300.0;
  CHECK_THROWS_WITH(roll_broken_loop(lat, cfg, LoopBreak::kActuator), Catch::Contains("cut-off"));
  cfg = loop_of("fast", -1e-3);
  CHECK_THROWS_WITH(roll_broken_loop(lat, cfg, LoopBreak::kActuator), Catch::Contains("latency"));
  cfg = loop_of("fast", 0.0);
  cfg.flap_pole_radps = 0.0;
  CHECK_THROWS_WITH(roll_broken_loop(lat, cfg, LoopBreak::kActuator), Catch::Contains("flap actuator"));
}

TEST_CASE("loop poles: pure delays sit at the origin and are counted, not listed", "[loop_margins]") {
  Eigen::MatrixXd phi = Eigen::MatrixXd::Zero(3, 3);
  phi(0, 0) = std::exp(-0.01);  // s = -1 at dt = 0.01
  phi(1, 2) = 1.0;              // a two-step delay line
  int origin = -1;
  const std::vector<LoopPole> poles = loop_poles(phi, 0.01, &origin);
  CHECK(origin == 2);
  REQUIRE(poles.size() == 1);
  CHECK(poles[0].s.real() == Approx(-1.0).epsilon(1e-9));
  CHECK(poles[0].damping == Approx(1.0));
}
