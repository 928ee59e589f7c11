#include "controller/yaw_loop.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nimble {
namespace {

int index_of(const std::vector<std::string>& names, const std::string& name, const char* what) {
  const auto it = std::find(names.begin(), names.end(), name);
  if (it == names.end()) {
    throw std::invalid_argument(std::string("yaw loop: the model has no ") + what + " '" + name + "'");
  }
  return static_cast<int>(it - names.begin());
}

void require_positive(double x, const char* name) {
  if (!(std::isfinite(x) && x > 0.0)) {
    throw std::invalid_argument(std::string("yaw loop: ") + name + " must be > 0, got " + std::to_string(x));
  }
}

}  // namespace

YawLoopOptions yaw_loop_options(const ControllerConfig& config, const std::string& gain_set) {
  YawLoopOptions o;
  o.roll_gains = roll_gain_set(config, gain_set);
  o.roll_cmd_to_delta_f_radps = config.roll_cmd_to_delta_f_radps;
  o.yaw_cmd_to_wing_root_rad = config.yaw_cmd_to_wing_root_rad;
  o.lowpass_cutoff_hz = config.roll_lowpass_cutoff_hz;
  return o;
}

Eigen::MatrixXd yaw_closed_loop_matrix(const StateSpace& lat4, const GainSet& yaw_gains, const YawLoopOptions& o) {
  if (lat4.states != std::vector<std::string>{"p", "r", "v", "phi"}) {
    throw std::invalid_argument("yaw loop: the model must have the states p r v phi (a lateral4 model)");
  }
  const int i_df = index_of(lat4.inputs, "delta_f", "input");
  const int i_dw = index_of(lat4.inputs, "delta_w", "input");
  require_positive(o.lowpass_cutoff_hz, "the low-pass cut-off");
  require_positive(o.flap_pole_radps, "the flap pole");
  require_positive(o.servo_wn2_rad2ps2, "the servo wn^2");
  require_positive(o.servo_c1_radps, "the servo damping term");

  // p r v phi psi df dw dw_rate lr lr_rate ly ly_rate
  enum { P, R, V, PHI, PSI, DF, DW, DWR, LR, LRR, LY, LYR, N };
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(N, N);
  A.block(0, 0, 4, 4) = lat4.A;
  A.block(0, DF, 4, 1) = lat4.B.col(i_df);
  A.block(0, DW, 4, 1) = lat4.B.col(i_dw);
  // psi_dot = r cos(phi0) / cos(theta0): the phi row of A holds tan(theta0) cos(phi0) for r,
  // and cos(phi0) / cos(theta0) = tan(theta0) cos(phi0) / sin(theta0) is not defined at theta0 = 0;
  // at the trims of the thesis (|theta0|, |phi0| < 5 deg) the factor is within 0.4 % of 1.
  A(PSI, R) = 1.0;

  const double wc = 2.0 * M_PI * o.lowpass_cutoff_hz;
  // Roll: LP input u_r = -(kp phi + kd p).
  A(LR, LRR) = 1.0;
  A(LRR, LR) = -wc * wc;
  A(LRR, LRR) = -std::sqrt(2.0) * wc;
  A(LRR, PHI) += wc * wc * -o.roll_gains.kp_per_rad;
  A(LRR, P) += wc * wc * -o.roll_gains.kd_per_radps;
  A(DF, DF) = -o.flap_pole_radps;
  A(DF, LR) = o.flap_gain_per_s * o.roll_cmd_to_delta_f_radps;
  // Yaw: LP input u_y = -(kp psi + kd r).
  A(LY, LYR) = 1.0;
  A(LYR, LY) = -wc * wc;
  A(LYR, LYR) = -std::sqrt(2.0) * wc;
  A(LYR, PSI) += wc * wc * -yaw_gains.kp_per_rad;
  A(LYR, R) += wc * wc * -yaw_gains.kd_per_radps;
  A(DW, DWR) = 1.0;
  A(DWR, DW) = -o.servo_wn2_rad2ps2;
  A(DWR, DWR) = -o.servo_c1_radps;
  A(DWR, LY) = o.servo_wn2_rad2ps2 * o.yaw_cmd_to_wing_root_rad;
  return A;
}

YawLoopPoles analyse_yaw_loop(const StateSpace& lat4, const GainSet& yaw_gains, const YawLoopOptions& options) {
  const Eigen::MatrixXd A = yaw_closed_loop_matrix(lat4, yaw_gains, options);
  const Eigen::VectorXcd eig = A.eigenvalues();
  YawLoopPoles r;
  for (int i = 0; i < eig.size(); ++i) r.poles_s.push_back(eig(i));
  std::sort(r.poles_s.begin(), r.poles_s.end(),
            [](const std::complex<double>& a, const std::complex<double>& b) { return a.real() < b.real(); });
  r.max_real_per_s = r.poles_s.back().real();
  r.stable = r.max_real_per_s < 0.0;
  for (const auto& s : r.poles_s) {
    if (std::fabs(s.imag()) > 1e-9) r.min_damping = std::min(r.min_damping, -s.real() / std::abs(s));
  }
  return r;
}

}  // namespace nimble
