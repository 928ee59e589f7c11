// Pitch loop on the longitudinal model of thesis Table E.4 (controller/pitch_loop.h):
// the linear closed loop matches the controller code, the shipped pitch gains are
// stable and well damped and the best of the calibration grid, and the former
// assumption (the slow roll gains) is unstable.

#include <algorithm>
#include <cmath>
#include <complex>
#include <string>
#include <vector>

#include <Eigen/Eigenvalues>
#include <catch2/catch.hpp>

#include "controller/attitude_controller.h"
#include "controller/pitch_loop.h"
#include "core/config.h"
#include "core/model.h"
#include "core/vehicle.h"

using namespace nimble;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

struct PitchRig {
  DerivativeModel model = load_model(kConfigs + "models/nimble_longitudinal.yaml");
  Vehicle vehicle = load_vehicle(model.vehicle_file);
  StateSpace lon = build_state_space(model, vehicle);
  ControllerConfig config = load_controller_config(kConfigs + "controller/nimble_attitude.yaml");
  PitchLoopOptions options = make_options(config);

  /// Controller options plus the servo of the shipped plant file.
  static PitchLoopOptions make_options(const ControllerConfig& config) {
    PitchLoopOptions o = pitch_loop_options(config);
    ConfigMap plant = ConfigMap::load_file(kConfigs + "plant/nimble_plant.yaml");
    ConfigMap servo = plant.get_map("servo");
    o.servo_wn2_rad2ps2 = servo.get_double("wn2_rad2ps2");
    o.servo_c1_radps = servo.get_double("c1_radps");
    return o;
  }
};

/// The gains used before the calibration: the slow roll set.
const GainSet kSlowRollGains{0.625, 0.156};

}  // namespace

TEST_CASE("pitch loop: zero gains leave the open-loop longitudinal modes and the servo", "[pitch_loop]") {
  const PitchRig rig;
  for (const bool continuous : {false, true}) {
    PitchLoopOptions o = rig.options;
    o.continuous = continuous;
    const PitchLoopPoles r = analyse_pitch_loop(rig.lon, GainSet{0.0, 0.0}, o);
    const Eigen::VectorXcd open = Eigen::EigenSolver<Eigen::MatrixXd>(rig.lon.A, false).eigenvalues();
    double max_open = -INFINITY;
    for (Eigen::Index i = 0; i < open.size(); ++i) {
      max_open = std::max(max_open, open(i).real());
      double nearest = INFINITY;
      for (const auto& s : r.poles_s) nearest = std::min(nearest, std::abs(s - open(i)));
      INFO((continuous ? "continuous" : "discrete") << ": open-loop eigenvalue " << open(i));
      CHECK(nearest < 1e-6 * std::max(1.0, std::abs(open(i))));
    }
    CHECK(max_open > 0.0);  // Table E.4: unstable oscillatory pair
    CHECK_FALSE(r.stable);
    CHECK(r.max_real_per_s == Approx(max_open).margin(1e-6));
  }
}

TEST_CASE("pitch loop: the discrete closed-loop matrix reproduces AttitudeController on the ZOH plant",
          "[pitch_loop]") {
  const PitchRig rig;
  ControllerConfig cfg = rig.config;
  cfg.pitch_gains = GainSet{0.2, 0.03};
  const PitchLoopOptions o = pitch_loop_options(cfg);
  const Eigen::MatrixXd Phi = pitch_closed_loop_matrix(rig.lon, cfg.pitch_gains, o);
  REQUIRE(Phi.rows() == 8);
  const StateSpace plant = pitch_plant_with_servo(rig.lon, o);
  const DiscreteStateSpace d = discretize_zoh(plant, cfg.dt_s());

  AttitudeController controller(cfg);  // references start at 0 with the set-points
  Eigen::VectorXd x = Eigen::VectorXd::Zero(6);
  x(3) = 0.05;  // theta
  x(0) = -0.2;  // q
  Eigen::VectorXd z = Eigen::VectorXd::Zero(8);
  z.head(6) = x;
  double max_diff = 0.0;
  for (int k = 0; k < 400; ++k) {
    ControllerInput in;
    in.q_radps = x(0);
    in.theta_rad = x(3);
    const ControllerOutput out = controller.step(in);
    REQUIRE(std::fabs(out.pitch_cmd_norm) < 1.0);  // linear range: no clipping
    x = d.Ad * x + d.Bd * out.dihedral_rad;
    z = Phi * z;
    max_diff = std::max(max_diff, (x - z.head(6)).cwiseAbs().maxCoeff());
  }
  CHECK(max_diff < 1e-9);
}

TEST_CASE("pitch loop: the shipped pitch gains are stable and well damped on the Table E.4 model",
          "[pitch_loop][calibration]") {
  const PitchRig rig;
  for (const bool continuous : {false, true}) {
    PitchLoopOptions o = rig.options;
    o.continuous = continuous;
    const PitchLoopPoles r = analyse_pitch_loop(rig.lon, rig.config.pitch_gains, o);
    INFO((continuous ? "continuous" : "discrete")
         << ": max real part " << r.max_real_per_s << " /s, min damping " << r.min_damping << " at " << r.least_damped);
    CHECK(r.stable);
    for (const auto& s : r.poles_s) CHECK(s.real() < 0.0);
    REQUIRE(r.has_oscillatory);
    CHECK(r.min_damping > 0.25);
  }
  // Still stable with one control period of command delay.
  PitchLoopOptions delayed = rig.options;
  delayed.delay_steps = 1;
  const PitchLoopPoles r = analyse_pitch_loop(rig.lon, rig.config.pitch_gains, delayed);
  CHECK(r.stable);
  CHECK(r.min_damping > 0.25);
}

TEST_CASE("pitch loop: the previous assumption (slow roll gains 0.625/0.156) is unstable", "[pitch_loop]") {
  const PitchRig rig;
  for (const bool continuous : {false, true}) {
    PitchLoopOptions o = rig.options;
    o.continuous = continuous;
    const PitchLoopPoles r = analyse_pitch_loop(rig.lon, kSlowRollGains, o);
    INFO((continuous ? "continuous" : "discrete") << ": max real part " << r.max_real_per_s);
    CHECK_FALSE(r.stable);
    CHECK(r.max_real_per_s > 1.0);
  }
}

TEST_CASE("pitch loop: the shipped pitch gains are the best of the calibration grid", "[pitch_loop][calibration]") {
  const PitchRig rig;
  const PitchGainScan scan = scan_pitch_gains(rig.lon, rig.options, default_pitch_kp_grid(), default_pitch_kd_grid());
  REQUIRE(scan.best.has_value());
  const PitchGainPoint& best = scan.points[*scan.best];
  const PitchLoopPoles shipped = analyse_pitch_loop(rig.lon, rig.config.pitch_gains, rig.options);
  INFO("best kp " << best.gains.kp_per_rad << " kd " << best.gains.kd_per_radps << " damping " << best.poles.min_damping
                  << "; shipped kp " << rig.config.pitch_gains.kp_per_rad << " kd "
                  << rig.config.pitch_gains.kd_per_radps << " damping " << shipped.min_damping);
  CHECK(best.poles.stable);
  CHECK(shipped.stable);
  CHECK(shipped.min_damping >= best.poles.min_damping - 0.01);
  // The grid point chosen is the one the scan reports as best: no stable point is better damped.
  for (const PitchGainPoint& p : scan.points) {
    if (p.poles.stable && p.poles.has_oscillatory) CHECK(p.poles.min_damping <= best.poles.min_damping);
  }
}

TEST_CASE("pitch loop: built-in pitch gains equal the shipped file", "[pitch_loop]") {
  const PitchRig rig;
  const ControllerConfig d;
  CHECK(d.pitch_gains.kp_per_rad == rig.config.pitch_gains.kp_per_rad);
  CHECK(d.pitch_gains.kd_per_radps == rig.config.pitch_gains.kd_per_radps);
  CHECK(d.pitch_cmd_to_dihedral_rad == rig.config.pitch_cmd_to_dihedral_rad);
}

TEST_CASE("pitch loop: bad inputs are rejected", "[pitch_loop]") {
  const PitchRig rig;
  PitchLoopOptions o = rig.options;
  o.lowpass_cutoff_hz = 0.6 * o.rate_hz;
  CHECK_THROWS_AS(analyse_pitch_loop(rig.lon, GainSet{0.1, 0.01}, o), std::invalid_argument);
  CHECK_THROWS_AS(analyse_pitch_loop(rig.lon, GainSet{-0.1, 0.01}, rig.options), std::invalid_argument);
  const DerivativeModel lateral = load_model(kConfigs + "models/nimble_lateral_set1.yaml");
  const StateSpace lat = build_state_space(lateral, rig.vehicle);
  CHECK_THROWS_AS(analyse_pitch_loop(lat, GainSet{0.1, 0.01}, rig.options), std::invalid_argument);
  CHECK_THROWS_AS(scan_pitch_gains(rig.lon, rig.options, {}, {0.01}), std::invalid_argument);
}
