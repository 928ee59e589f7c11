#include "controller/roll_loop.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

#include "controller/low_pass.h"
#include "core/constants.h"
#include "core/config.h"

namespace nimble {
namespace {

constexpr int kP = 0, kPhi = 2, kPlant = 4;  // [p v phi delta_f]

/// What the assembled system is for.
enum class Mode { kActuator, kPhi, kP, kSetpoint };

Mode mode_of(LoopBreak b) {
  switch (b) {
    case LoopBreak::kPhi: return Mode::kPhi;
    case LoopBreak::kP: return Mode::kP;
    case LoopBreak::kActuator: break;
  }
  return Mode::kActuator;
}

/// A signal of one control step: x . state + w . input.
struct Lin {
  Eigen::RowVectorXd x;
  double w = 0.0;
  Lin operator+(const Lin& o) const { return {x + o.x, w + o.w}; }
  Lin operator-(const Lin& o) const { return {x - o.x, w - o.w}; }
  Lin operator*(double k) const { return {x * k, w * k}; }
};

/// The assembled loop: state transition, input, and the signals of a step.
struct Assembled {
  Eigen::MatrixXd A;
  Eigen::VectorXd B;
  Lin phi, p, cmd, phi_ref;
  double dt_s = 0.0;
};

void check_config(const RollLoopConfig& c) {
  if (!(std::isfinite(c.rate_hz) && c.rate_hz > 0.0)) {
    throw std::invalid_argument("roll loop: rate must be > 0 Hz, got " + general_text(c.rate_hz));
  }
  if (!(std::isfinite(c.lowpass_cutoff_hz) && c.lowpass_cutoff_hz > 0.0 && c.lowpass_cutoff_hz < 0.5 * c.rate_hz)) {
    throw std::invalid_argument("roll loop: low-pass cut-off must be in (0, rate/2), got " +
                                general_text(c.lowpass_cutoff_hz) + " Hz");
  }
  if (!(std::isfinite(c.latency_s) && c.latency_s >= 0.0 && c.latency_s <= 1.0)) {
    throw std::invalid_argument("roll loop: latency must be in [0, 1] s, got " + general_text(c.latency_s));
  }
  if (!(std::isfinite(c.gains.kp_per_rad) && std::isfinite(c.gains.kd_per_radps) &&
        std::isfinite(c.roll_cmd_to_delta_f_radps))) {
    throw std::invalid_argument("roll loop: gains and command map must be finite");
  }
}

Assembled assemble(const StateSpace& lateral, const RollLoopConfig& c, Mode mode) {
  check_config(c);
  const StateSpace plant = roll_plant_with_actuator(lateral, c);
  const double T = 1.0 / c.rate_hz;
  // latency = n T + f, 0 <= f < T.
  int n_delay = static_cast<int>(std::floor(c.latency_s / T + 1e-9));
  double f = c.latency_s - n_delay * T;
  if (f < 1e-12 * T) f = 0.0;
  const int m = n_delay + (f > 0.0 ? 1 : 0);
  Eigen::MatrixXd Ad;
  Eigen::VectorXd G0, G1 = Eigen::VectorXd::Zero(kPlant);
  if (f == 0.0) {
    const DiscreteStateSpace d = discretize_zoh(plant, T);
    Ad = d.Ad;
    G0 = d.Bd.col(0);
  } else {
    const DiscreteStateSpace late = discretize_zoh(plant, T - f), early = discretize_zoh(plant, f);
    Ad = late.Ad * early.Ad;
    G0 = late.Bd.col(0);
    G1 = late.Ad * early.Bd.col(0);
  }
  const bool setpoint = mode == Mode::kSetpoint;
  const int i_buf = kPlant, i_s1 = kPlant + m, i_s2 = i_s1 + 1, i_gen = i_s2 + 1;
  const int n = i_gen + (setpoint ? 3 : 0);
  auto unit = [n](int i) {
    Lin s{Eigen::RowVectorXd::Zero(n), 0.0};
    s.x(i) = 1.0;
    return s;
  };
  const Lin zero{Eigen::RowVectorXd::Zero(n), 0.0};
  const Lin input{Eigen::RowVectorXd::Zero(n), 1.0};

  Assembled a;
  a.dt_s = T;
  a.phi = unit(kPhi);
  a.p = unit(kP);
  // The generator's state before this step's update; the controller uses the updated one.
  const Lin ref_angle = setpoint ? unit(i_gen) + unit(i_gen + 1) * T : zero;
  const Lin ref_rate = setpoint ? unit(i_gen + 1) + unit(i_gen + 2) * T : zero;
  a.phi_ref = ref_angle;
  const Lin phi_ctrl = mode == Mode::kPhi ? input : a.phi;
  const Lin p_ctrl = mode == Mode::kP ? input : a.p;
  const Lin pd = (ref_angle - phi_ctrl) * c.gains.kp_per_rad + (ref_rate - p_ctrl) * c.gains.kd_per_radps;
  const LowPassCoefficients lp = SecondOrderLowPass(c.lowpass_cutoff_hz, c.rate_hz).coefficients();
  const Lin out = pd * lp.b0 + unit(i_s1);
  a.cmd = out * c.roll_cmd_to_delta_f_radps;
  const Lin u_now = mode == Mode::kActuator ? input : a.cmd;
  auto issued = [&](int j) { return j == 0 ? u_now : unit(i_buf + j - 1); };  // u[k - j]

  a.A = Eigen::MatrixXd::Zero(n, n);
  a.B = Eigen::VectorXd::Zero(n);
  auto set_row = [&](int row, const Lin& s) {
    a.A.row(row) = s.x;
    a.B(row) = s.w;
  };
  for (int r = 0; r < kPlant; ++r) {
    Lin next = zero;
    next.x.head(kPlant) = Ad.row(r);
    next = next + issued(n_delay) * G0(r);
    if (f > 0.0) next = next + issued(n_delay + 1) * G1(r);
    set_row(r, next);
  }
  for (int j = 0; j < m; ++j) set_row(i_buf + j, issued(j));
  set_row(i_s1, pd * lp.b1 - out * lp.a1 + unit(i_s2));
  set_row(i_s2, pd * lp.b2 - out * lp.a2);
  if (setpoint) {
    const double w = c.reference.omega_radps, z = c.reference.zeta;
    const Lin angle = unit(i_gen), rate = unit(i_gen + 1), accel = unit(i_gen + 2);
    const Lin angle_next = angle + rate * T, rate_next = rate + accel * T;
    set_row(i_gen, angle_next);
    set_row(i_gen + 1, rate_next);
    set_row(i_gen + 2, rate_next * (-2.0 * z * w) - angle_next * (w * w) + input * (w * w));
  }
  return a;
}

/// First frequency where |h(w)| / |h(0)| falls below 1/sqrt(2), refined by bisection; the
/// Nyquist frequency if it never does [Hz].
template <typename F>
double bandwidth_hz(const F& h, double nyquist) {
  const double dc = std::abs(h(0.0));
  if (!(dc > 0.0) || !std::isfinite(dc)) return 0.0;
  auto excess = [&](double x) { return std::abs(h(x)) / dc - 1.0 / std::sqrt(2.0); };
  const int n = 400;
  const double w_min = 2.0 * kPi * 0.01;
  double prev = w_min;
  if (excess(prev) < 0.0) return prev / (2.0 * kPi);
  for (int i = 1; i < n; ++i) {
    const double x = w_min * std::pow(nyquist / w_min, static_cast<double>(i) / (n - 1));
    if (excess(x) < 0.0) return bisect_sign_change(excess, prev, x) / (2.0 * kPi);
    prev = x;
  }
  return nyquist / (2.0 * kPi);
}

BrokenLoop as_broken(const Assembled& a, const Lin& output) {
  BrokenLoop b;
  b.A = a.A;
  b.B = a.B;
  b.C = output.x;
  b.D = output.w;
  b.dt_s = a.dt_s;
  return b;
}

}  // namespace

std::string to_string(LoopBreak b) {
  switch (b) {
    case LoopBreak::kPhi: return "phi";
    case LoopBreak::kP: return "p";
    case LoopBreak::kActuator: break;
  }
  return "actuator";
}

RollLoopConfig roll_loop_config(const ControllerConfig& controller, const GainSet& gains) {
  RollLoopConfig c;
  c.gains = gains;
  c.rate_hz = controller.rate_hz;
  c.lowpass_cutoff_hz = controller.roll_lowpass_cutoff_hz;
  c.roll_cmd_to_delta_f_radps = controller.roll_cmd_to_delta_f_radps;
  c.reference = controller.roll_reference;
  return c;
}

StateSpace roll_plant_with_actuator(const StateSpace& lateral, const RollLoopConfig& config) {
  const std::vector<std::string> expected{"p", "v", "phi"};
  if (lateral.states != expected || lateral.A.rows() != 3) {
    throw std::invalid_argument(
        "roll loop: the model must be lateral3 (states p v phi); a lateral4 model's roll and yaw loops are one loop "
        "(controller/yaw_loop.h)");
  }
  const auto it = std::find(lateral.inputs.begin(), lateral.inputs.end(), "delta_f");
  if (it == lateral.inputs.end()) throw std::invalid_argument("roll loop: the model has no delta_f input");
  const Eigen::Index i_df = it - lateral.inputs.begin();
  if (!(config.flap_pole_radps > 0.0 && config.flap_gain_per_s > 0.0 && std::isfinite(config.flap_pole_radps) &&
        std::isfinite(config.flap_gain_per_s))) {
    throw std::invalid_argument("roll loop: the flap actuator's gain and pole must be > 0");
  }
  StateSpace ss;
  ss.A = Eigen::MatrixXd::Zero(kPlant, kPlant);
  ss.B = Eigen::MatrixXd::Zero(kPlant, 1);
  ss.A.topLeftCorner(3, 3) = lateral.A;
  ss.A.block(0, 3, 3, 1) = lateral.B.col(i_df);
  ss.A(3, 3) = -config.flap_pole_radps;
  ss.B(3, 0) = config.flap_gain_per_s;
  ss.states = {"p", "v", "phi", "delta_f"};
  ss.state_units = {"rad/s", "m/s", "rad", "rad/s"};
  ss.inputs = {"delta_f_cmd"};
  ss.input_units = {"rad/s"};
  return ss;
}

BrokenLoop roll_broken_loop(const StateSpace& lateral, const RollLoopConfig& config, LoopBreak where) {
  const Assembled a = assemble(lateral, config, mode_of(where));
  switch (where) {
    case LoopBreak::kPhi: return as_broken(a, a.phi);
    case LoopBreak::kP: return as_broken(a, a.p);
    case LoopBreak::kActuator: break;
  }
  return as_broken(a, a.cmd);
}

SetpointLoop roll_setpoint_loop(const StateSpace& lateral, const RollLoopConfig& config) {
  const Assembled a = assemble(lateral, config, Mode::kSetpoint);
  SetpointLoop s;
  s.A = a.A;
  s.B = a.B;
  s.phi = a.phi.x;
  s.phi_ref = a.phi_ref.x;
  s.p = a.p.x;
  s.delta_f_cmd = a.cmd.x;
  s.dt_s = a.dt_s;
  return s;
}

StepResponse roll_step_response(const SetpointLoop& loop, double step_rad, double duration_s) {
  StepResponse r;
  Eigen::VectorXd x = Eigen::VectorXd::Zero(loop.A.rows());
  const long steps = static_cast<long>(std::ceil(duration_s / loop.dt_s));
  for (long k = 0; k <= steps; ++k) {
    r.t_s.push_back(static_cast<double>(k) * loop.dt_s);
    r.phi_rad.push_back(loop.phi.dot(x));
    r.phi_ref_rad.push_back(loop.phi_ref.dot(x));
    r.p_radps.push_back(loop.p.dot(x));
    r.delta_f_cmd_radps.push_back(loop.delta_f_cmd.dot(x));
    x = loop.A * x + loop.B * step_rad;
  }
  return r;
}

RollLoopAnalysis analyse_roll_loop(const StateSpace& lateral, const RollLoopConfig& config, LoopBreak where,
                                   const MarginOptions& options, bool full) {
  RollLoopAnalysis r;
  const BrokenLoop broken = roll_broken_loop(lateral, config, where);
  r.margins = loop_margins(broken, options);
  r.saturation_error_rad = config.gains.kp_per_rad > 0.0 ? 1.0 / config.gains.kp_per_rad : INFINITY;
  if (!full) return r;
  const BrokenLoop at_actuator =
      where == LoopBreak::kActuator ? broken : roll_broken_loop(lateral, config, LoopBreak::kActuator);
  r.poles = loop_poles(closed_loop_matrix(at_actuator), at_actuator.dt_s, &r.poles_at_origin);
  const double nyquist = kPi / broken.dt_s;
  for (const LoopPole& p : r.poles) {
    if (p.s.imag() > 1e-9 && p.s.imag() < 0.999 * nyquist && (!r.has_dominant_pair || p.damping < r.dominant.damping)) {
      r.dominant = p;
      r.has_dominant_pair = true;
    }
  }
  const SetpointLoop sp = roll_setpoint_loop(lateral, config);
  const LoopResponse phi_of_r(BrokenLoop{sp.A, sp.B, sp.phi, 0.0, sp.dt_s});
  const LoopResponse ref_of_r(BrokenLoop{sp.A, sp.B, sp.phi_ref, 0.0, sp.dt_s});
  auto tracking = [&](double w) { return phi_of_r.open(w) / ref_of_r.open(w); };
  r.dc_gain = std::abs(tracking(0.0));
  r.bandwidth_hz = bandwidth_hz(tracking, nyquist);
  r.setpoint_bandwidth_hz = bandwidth_hz([&](double w) { return phi_of_r.open(w); }, nyquist);
  return r;
}

RollLoopResponse roll_loop_response(const StateSpace& lateral, const RollLoopConfig& config, LoopBreak where,
                                    const std::vector<double>& omega_radps) {
  const LoopResponse loop(roll_broken_loop(lateral, config, where));
  const SetpointLoop sp = roll_setpoint_loop(lateral, config);
  const LoopResponse phi_of_r(BrokenLoop{sp.A, sp.B, sp.phi, 0.0, sp.dt_s});
  const LoopResponse ref_of_r(BrokenLoop{sp.A, sp.B, sp.phi_ref, 0.0, sp.dt_s});
  RollLoopResponse r;
  r.omega_radps = omega_radps;
  for (const double w : omega_radps) {
    r.ratio.push_back(loop.ratio(w));
    r.tracking.push_back(phi_of_r.open(w) / ref_of_r.open(w));
  }
  return r;
}

namespace {

/// PD gains for `request` on the loop `config` (its cut-off as it is), or why there are none.
RollDesign try_design(const StateSpace& lateral, const RollLoopConfig& config, const DesignRequest& request) {
  RollDesign d;
  d.lowpass_cutoff_hz = config.lowpass_cutoff_hz;
  const std::string with = "with the " + general_text(config.lowpass_cutoff_hz) + " Hz low-pass ";
  const double w = 2.0 * kPi * request.crossover_hz;
  const std::complex<double> target = std::polar(1.0, (-180.0 + request.phase_margin_deg) * kPi / 180.0);
  // L is linear in (kp, kd): L = kp L(1, 0) + kd L(0, 1).
  RollLoopConfig c = config;
  c.gains = {1.0, 0.0};
  const std::complex<double> a = LoopResponse(roll_broken_loop(lateral, c, LoopBreak::kActuator)).ratio(w);
  c.gains = {0.0, 1.0};
  const std::complex<double> b = LoopResponse(roll_broken_loop(lateral, c, LoopBreak::kActuator)).ratio(w);
  const double det = a.real() * b.imag() - b.real() * a.imag();
  if (std::abs(det) < 1e-300) {
    d.note = "the gains cannot shape the loop at " + general_text(request.crossover_hz) + " Hz";
    return d;
  }
  const double kp = (target.real() * b.imag() - b.real() * target.imag()) / det;
  const double kd = (a.real() * target.imag() - target.real() * a.imag()) / det;
  d.gains = {kp, kd};
  if (kp < 0.0 || kd < 0.0) {
    d.note = with + "it needs kp " + general_text(kp) + ", kd " + general_text(kd) + ": a negative gain";
    return d;
  }
  c.gains = d.gains;
  d.analysis = analyse_roll_loop(lateral, c);
  if (!d.analysis.margins.closed_loop_stable) {
    d.note = with + "kp " + general_text(kp) + ", kd " + general_text(kd) + " leave the closed loop unstable";
  } else if (std::abs(d.analysis.margins.phase_margin_deg - request.phase_margin_deg) > 1.0) {
    d.note = with + "another crossover (" + general_text(d.analysis.margins.crossover_hz) +
             " Hz) has the smaller phase margin, " + general_text(d.analysis.margins.phase_margin_deg) + " deg";
  } else if (d.analysis.dc_gain < request.min_dc_gain) {
    d.note = with + "kp " + general_text(kp) + ", kd " + general_text(kd) + " track phi_ref at 0 Hz only by " +
             general_text(d.analysis.dc_gain) + " (at least " + general_text(request.min_dc_gain) + " asked)";
  } else {
    d.feasible = true;
  }
  return d;
}

}  // namespace

RollDesign design_roll_gains(const StateSpace& lateral, const RollLoopConfig& config, const DesignRequest& request) {
  if (!(request.phase_margin_deg > 0.0 && request.phase_margin_deg < 90.0)) {
    throw std::invalid_argument("design: phase_margin_deg must be in (0, 90), got " +
                                general_text(request.phase_margin_deg));
  }
  if (!(request.crossover_hz > 0.0 && request.crossover_hz < config.rate_hz / 4.0)) {
    throw std::invalid_argument("design: crossover_hz must be in (0, " + general_text(config.rate_hz / 4.0) +
                                "), got " + general_text(request.crossover_hz));
  }
  std::vector<double> cutoffs{config.lowpass_cutoff_hz};
  for (const double f : {20.0, 25.0, 30.0, 40.0, 50.0, 64.0}) {
    if (f > config.lowpass_cutoff_hz && f <= config.rate_hz / 8.0) cutoffs.push_back(f);
  }
  std::string first_why;
  for (const double cutoff : cutoffs) {
    RollLoopConfig c = config;
    c.lowpass_cutoff_hz = cutoff;
    RollDesign d = try_design(lateral, c, request);
    if (d.feasible) {
      d.note = cutoff == config.lowpass_cutoff_hz
                   ? "on the configured " + general_text(cutoff) + " Hz low-pass"
                   : "the low-pass cut-off raised from " + general_text(config.lowpass_cutoff_hz) + " to " +
                         general_text(cutoff) + " Hz: " + first_why;
      return d;
    }
    if (first_why.empty()) first_why = d.note;
  }
  // Where the request can be met: the crossovers at which it is feasible on the configured loop.
  RollDesign none;
  none.note = "no PD gains reach it up to a " + general_text(cutoffs.back()) + " Hz low-pass (" + first_why + ")";
  DesignRequest probe = request;
  double lo = 0.0, hi = 0.0;
  for (int i = 0; i <= 80; ++i) {
    probe.crossover_hz = 0.1 * std::pow(100.0, i / 80.0);  // 0.1 .. 10 Hz
    if (probe.crossover_hz >= config.rate_hz / 4.0) break;
    if (try_design(lateral, config, probe).feasible) {
      if (lo == 0.0) lo = probe.crossover_hz;
      hi = probe.crossover_hz;
    }
  }
  none.note += lo > 0.0 ? "; with the " + general_text(config.lowpass_cutoff_hz) + " Hz low-pass a " +
                              general_text(request.phase_margin_deg) + " deg margin is reached at crossovers " +
                              general_text(lo) + " to " + general_text(hi) + " Hz"
                        : "; with the " + general_text(config.lowpass_cutoff_hz) +
                              " Hz low-pass no crossover from 0.1 to 10 Hz "
                              "reaches a " +
                              general_text(request.phase_margin_deg) + " deg margin";
  return none;
}

}  // namespace nimble
