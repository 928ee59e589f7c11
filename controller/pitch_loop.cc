#include "controller/pitch_loop.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "controller/low_pass.h"
#include "core/constants.h"

namespace nimble {
namespace {

constexpr int kPlantStates = 6;  // q u w theta delta_d delta_d_rate
constexpr int kQ = 0, kTheta = 3;

int index_of(const std::vector<std::string>& names, const std::string& name) {
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (names[i] == name) return static_cast<int>(i);
  }
  return -1;
}

void check_options(const GainSet& gains, const PitchLoopOptions& o) {
  if (!(std::isfinite(o.rate_hz) && o.rate_hz > 0.0)) {
    throw std::invalid_argument("pitch loop: rate must be > 0 Hz, got " + std::to_string(o.rate_hz));
  }
  if (!(std::isfinite(o.lowpass_cutoff_hz) && o.lowpass_cutoff_hz > 0.0 && o.lowpass_cutoff_hz < 0.5 * o.rate_hz)) {
    throw std::invalid_argument("pitch loop: low-pass cut-off must be in (0, rate/2), got " +
                                std::to_string(o.lowpass_cutoff_hz));
  }
  if (!(std::isfinite(o.pitch_cmd_to_dihedral_rad) && o.pitch_cmd_to_dihedral_rad >= 0.0)) {
    throw std::invalid_argument("pitch loop: dihedral map must be >= 0, got " +
                                std::to_string(o.pitch_cmd_to_dihedral_rad));
  }
  if (!(std::isfinite(gains.kp_per_rad) && gains.kp_per_rad >= 0.0 && std::isfinite(gains.kd_per_radps) &&
        gains.kd_per_radps >= 0.0)) {
    throw std::invalid_argument("pitch loop: gains must be finite and >= 0");
  }
  if (o.delay_steps < 0) throw std::invalid_argument("pitch loop: delay_steps must be >= 0");
}

}  // namespace

PitchLoopOptions pitch_loop_options(const ControllerConfig& config) {
  PitchLoopOptions o;
  o.rate_hz = config.rate_hz;
  o.lowpass_cutoff_hz = config.pitch_lowpass_cutoff_hz;
  o.pitch_cmd_to_dihedral_rad = config.pitch_cmd_to_dihedral_rad;
  return o;
}

StateSpace pitch_plant_with_servo(const StateSpace& lon, const PitchLoopOptions& options) {
  const std::vector<std::string> expected{"q", "u", "w", "theta"};
  if (lon.states != expected || lon.A.rows() != 4 || lon.A.cols() != 4) {
    throw std::invalid_argument("pitch loop: the model must have the longitudinal states q u w theta");
  }
  const int i_dd = index_of(lon.inputs, "delta_d");
  if (i_dd < 0 || i_dd >= lon.B.cols()) {
    throw std::invalid_argument("pitch loop: the longitudinal model has no delta_d (dihedral) input");
  }
  if (!(options.servo_wn2_rad2ps2 > 0.0 && options.servo_c1_radps > 0.0 && std::isfinite(options.servo_wn2_rad2ps2) &&
        std::isfinite(options.servo_c1_radps))) {
    throw std::invalid_argument("pitch loop: servo wn2 and c1 must be positive");
  }
  StateSpace ss;
  ss.A = Eigen::MatrixXd::Zero(kPlantStates, kPlantStates);
  ss.B = Eigen::MatrixXd::Zero(kPlantStates, 1);
  ss.A.topLeftCorner(4, 4) = lon.A;
  ss.A.block(0, 4, 4, 1) = lon.B.col(i_dd);
  ss.A(4, 5) = 1.0;
  ss.A(5, 4) = -options.servo_wn2_rad2ps2;
  ss.A(5, 5) = -options.servo_c1_radps;
  ss.B(5, 0) = options.servo_wn2_rad2ps2;
  ss.states = {"q", "u", "w", "theta", "delta_d", "delta_d_rate"};
  ss.state_units = lon.state_units;
  ss.state_units.push_back("rad");
  ss.state_units.push_back("rad/s");
  ss.inputs = {"dihedral_cmd"};
  ss.input_units = {"rad"};
  return ss;
}

Eigen::MatrixXd pitch_closed_loop_matrix(const StateSpace& lon, const GainSet& gains, const PitchLoopOptions& options) {
  check_options(gains, options);
  const StateSpace plant = pitch_plant_with_servo(lon, options);
  const double map = options.pitch_cmd_to_dihedral_rad;
  // PD output pd = -K x over the plant states.
  Eigen::RowVectorXd K = Eigen::RowVectorXd::Zero(kPlantStates);
  K(kQ) = gains.kd_per_radps;
  K(kTheta) = gains.kp_per_rad;

  if (options.continuous) {
    // Analogue Butterworth: yddot = wc^2 (pd - y) - sqrt(2) wc ydot; dihedral_cmd = map y.
    const double wc = 2.0 * kPi * options.lowpass_cutoff_hz;
    const int n = kPlantStates + 2;
    Eigen::MatrixXd A = Eigen::MatrixXd::Zero(n, n);
    A.topLeftCorner(kPlantStates, kPlantStates) = plant.A;
    A.block(0, kPlantStates, kPlantStates, 1) = plant.B * map;
    A(kPlantStates, kPlantStates + 1) = 1.0;
    A.block(kPlantStates + 1, 0, 1, kPlantStates) = -wc * wc * K;
    A(kPlantStates + 1, kPlantStates) = -wc * wc;
    A(kPlantStates + 1, kPlantStates + 1) = -std::sqrt(2.0) * wc;
    return A;
  }

  const double dt = 1.0 / options.rate_hz;
  const DiscreteStateSpace d = discretize_zoh(plant, dt);
  const LowPassCoefficients c = SecondOrderLowPass(options.lowpass_cutoff_hz, options.rate_hz).coefficients();
  const int nd = options.delay_steps;
  const int i_s1 = kPlantStates, i_s2 = kPlantStates + 1, i_delay = kPlantStates + 2;
  const int n = kPlantStates + 2 + nd;
  // Filter output y = b0 pd + s1 = -b0 K x + s1; command = map y.
  Eigen::RowVectorXd y = Eigen::RowVectorXd::Zero(n);
  y.head(kPlantStates) = -c.b0 * K;
  y(i_s1) = 1.0;
  Eigen::MatrixXd Phi = Eigen::MatrixXd::Zero(n, n);
  // Command applied over this period: the current one, or the oldest held one.
  Eigen::RowVectorXd applied = Eigen::RowVectorXd::Zero(n);
  if (nd == 0) {
    applied = map * y;
  } else {
    applied(i_delay + nd - 1) = 1.0;
  }
  Phi.topLeftCorner(kPlantStates, kPlantStates) = d.Ad;
  Phi.topRows(kPlantStates) += d.Bd * applied;
  // s1' = b1 pd - a1 y + s2; s2' = b2 pd - a2 y (transposed direct form II).
  Phi.row(i_s1).head(kPlantStates) = -c.b1 * K;
  Phi.row(i_s1) -= c.a1 * y;
  Phi(i_s1, i_s2) += 1.0;
  Phi.row(i_s2).head(kPlantStates) = -c.b2 * K;
  Phi.row(i_s2) -= c.a2 * y;
  // Delay line: first holds this period's command, each later one its predecessor.
  for (int j = 0; j < nd; ++j) {
    if (j == 0) {
      Phi.row(i_delay) = map * y;
    } else {
      Phi(i_delay + j, i_delay + j - 1) = 1.0;
    }
  }
  return Phi;
}

PitchLoopPoles analyse_pitch_loop(const StateSpace& lon, const GainSet& gains, const PitchLoopOptions& options) {
  const Eigen::MatrixXd M = pitch_closed_loop_matrix(lon, gains, options);
  const Eigen::EigenSolver<Eigen::MatrixXd> solver(M, false);
  if (solver.info() != Eigen::Success) throw std::runtime_error("pitch loop: eigenvalue solver failed");
  PitchLoopPoles out;
  out.stable = true;
  out.max_real_per_s = -INFINITY;
  out.min_damping = INFINITY;
  for (Eigen::Index i = 0; i < solver.eigenvalues().size(); ++i) {
    const std::complex<double> e = solver.eigenvalues()(i);
    std::complex<double> s;
    if (options.continuous) {
      s = e;
      if (!(e.real() < 0.0)) out.stable = false;
    } else {
      if (!(std::abs(e) < 1.0)) out.stable = false;
      // z = 0 (a pure delay state with nothing behind it) is infinitely fast and real.
      s = std::abs(e) < 1e-300 ? std::complex<double>(-INFINITY, 0.0) : std::log(e) * options.rate_hz;
    }
    out.poles_s.push_back(s);
    out.max_real_per_s = std::max(out.max_real_per_s, s.real());
    if (e.imag() != 0.0 && std::isfinite(s.real())) {
      out.has_oscillatory = true;
      const double zeta = -s.real() / std::abs(s);
      if (zeta < out.min_damping) {
        out.min_damping = zeta;
        out.least_damped = std::complex<double>(s.real(), std::fabs(s.imag()));
      }
    }
  }
  if (!out.has_oscillatory) out.min_damping = 1.0;
  std::sort(out.poles_s.begin(), out.poles_s.end(), [](const auto& a, const auto& b) {
    return a.real() != b.real() ? a.real() > b.real() : a.imag() > b.imag();
  });
  return out;
}

PitchGainScan scan_pitch_gains(const StateSpace& lon, const PitchLoopOptions& options,
                               const std::vector<double>& kp_values, const std::vector<double>& kd_values) {
  if (kp_values.empty() || kd_values.empty()) throw std::invalid_argument("pitch gain scan: empty grid");
  PitchGainScan scan;
  scan.points.reserve(kp_values.size() * kd_values.size());
  for (const double kp : kp_values) {
    for (const double kd : kd_values) {
      const GainSet g{kp, kd};
      scan.points.push_back({g, analyse_pitch_loop(lon, g, options)});
      const PitchGainPoint& p = scan.points.back();
      if (p.poles.stable && p.poles.has_oscillatory &&
          (!scan.best || p.poles.min_damping > scan.points[*scan.best].poles.min_damping)) {
        scan.best = scan.points.size() - 1;
      }
    }
  }
  return scan;
}

std::vector<double> default_pitch_kp_grid() {
  std::vector<double> v;
  for (int i = 1; i <= 60; ++i) v.push_back(0.005 * i);
  return v;
}

std::vector<double> default_pitch_kd_grid() {
  std::vector<double> v;
  for (int i = 1; i <= 80; ++i) v.push_back(0.0005 * i);
  return v;
}

}  // namespace nimble
