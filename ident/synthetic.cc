#include "ident/synthetic.h"

#include <cmath>
#include <random>
#include <stdexcept>
#include <string>

namespace nimble::ident {
namespace {

/// +amplitude in the first half of [start, start + 1/f), -amplitude in the second, 0 outside.
double doublet(double t, double start, double f_hz, double amplitude) {
  const double half = 0.5 / f_hz;
  if (t < start || t >= start + 2.0 * half) return 0.0;
  return t < start + half ? amplitude : -amplitude;
}

double throttle_pct(const SyntheticOptions& o, double t) {
  if (o.throttle_amplitude_pct == 0.0 || t < o.hover_s || t > o.duration_s - o.tail_hover_s) return 0.0;
  const double phase = std::fmod(t - o.hover_s, o.throttle_period_s);
  return doublet(phase, 0.5 * o.throttle_period_s, o.throttle_frequency_hz, o.throttle_amplitude_pct);
}

void check_positive(double x, const char* name) {
  if (!(x > 0.0) || !std::isfinite(x)) {
    throw std::invalid_argument(std::string("synthetic data: ") + name + " must be positive, got " + std::to_string(x));
  }
}

}  // namespace

double doublet_train_rad(const SyntheticOptions& o, double t_s) {
  if (o.doublet_frequencies_hz.empty()) return 0.0;
  const double end = o.duration_s - o.tail_hover_s;
  double start = o.hover_s;
  for (std::size_t k = 0; start < end; ++k) {
    const double f = o.doublet_frequencies_hz[k % o.doublet_frequencies_hz.size()];
    const double length = 1.0 / f;
    if (start + length > end) break;
    if (t_s < start) return 0.0;
    if (t_s < start + length) return doublet(t_s, start, f, o.doublet_amplitude_rad);
    start += length + o.doublet_gap_s;
  }
  return 0.0;
}

FlightData simulate_synthetic(const DerivativeModel& model, const Vehicle& vehicle, const SyntheticOptions& o) {
  if (model.structure != Structure::kLateral3 && model.structure != Structure::kLateral4) {
    throw std::invalid_argument("synthetic data: model " + model.name + " is not lateral3 or lateral4");
  }
  int i_f = -1, i_t = -1;
  for (std::size_t j = 0; j < model.inputs.size(); ++j) {
    if (model.inputs[j] == "delta_f")
      i_f = static_cast<int>(j);
    else if (model.inputs[j] == "delta_t")
      i_t = static_cast<int>(j);
    else
      throw std::invalid_argument("synthetic data: input '" + model.inputs[j] +
                                  "' is not simulated (delta_f, delta_t)");
  }
  if (i_f < 0) throw std::invalid_argument("synthetic data: model " + model.name + " has no delta_f input");
  check_positive(o.duration_s, "duration_s");
  check_positive(o.rate_hz, "rate_hz");
  check_positive(o.actuator_pole_radps, "actuator_pole_radps");
  for (double f : o.doublet_frequencies_hz) check_positive(f, "doublet frequency");
  check_positive(o.throttle_frequency_hz, "throttle_frequency_hz");
  check_positive(o.throttle_period_s, "throttle_period_s");

  const StateSpace ss = build_state_space(model, vehicle);
  const bool lat4 = model.structure == Structure::kLateral4;
  const Eigen::Index nx = ss.A.rows();
  const Eigen::Index ip = 0, ir = lat4 ? 1 : -1, iv = lat4 ? 2 : 1, iphi = lat4 ? 3 : 2;
  // Augmented state z = [x; delta_f; delta_t], inputs c = [delta_f_cmd; delta_t_cmd; wL; (wN;) wY].
  const Eigen::Index nz = nx + 2;
  const Eigen::Index nw = lat4 ? 3 : 2;
  const Eigen::Index nc = 2 + nw;
  const double a = o.actuator_pole_radps;
  StateSpace aug;
  aug.A = Eigen::MatrixXd::Zero(nz, nz);
  aug.B = Eigen::MatrixXd::Zero(nz, nc);
  aug.A.topLeftCorner(nx, nx) = ss.A;
  aug.A.block(0, nx, nx, 1) = ss.B.col(i_f);
  if (i_t >= 0) aug.A.block(0, nx + 1, nx, 1) = ss.B.col(i_t);
  aug.A(nx, nx) = -a;
  aug.A(nx + 1, nx + 1) = -a;
  aug.B(nx, 0) = a;
  aug.B(nx + 1, 1) = a;
  const double Ic = vehicle.Ic();
  aug.B(ip, 2) = vehicle.Izz_kgm2 / Ic;            // L disturbance (decoupled form)
  if (lat4) aug.B(ir, 3) = vehicle.Ixx_kgm2 / Ic;  // N disturbance
  aug.B(iv, 2 + nw - 1) = 1.0 / vehicle.mass_kg;   // Y disturbance
  const double dt = 1.0 / o.rate_hz;
  const DiscreteStateSpace d = discretize_zoh(aug, dt);

  // Closed loop of the feedback law, checked before flying.
  Eigen::MatrixXd K = Eigen::MatrixXd::Zero(nc, nz);
  K(0, iphi) = -o.k_phi_radps_per_rad;
  K(0, ip) = -o.k_p_radps_per_radps;
  const Eigen::MatrixXd closed = d.Ad + d.Bd * K;
  const double radius = closed.eigenvalues().cwiseAbs().maxCoeff();
  if (!(radius < 1.0)) {
    throw std::invalid_argument("synthetic data: the roll PD gains do not stabilise model " + model.name +
                                " (spectral radius " + std::to_string(radius) + ")");
  }

  std::mt19937_64 rng(o.seed);
  std::normal_distribution<double> normal(0.0, 1.0);
  const auto noise = [&](double sd) { return sd > 0.0 ? sd * normal(rng) : 0.0; };

  const std::size_t n = static_cast<std::size_t>(std::floor(o.duration_s * o.rate_hz)) + 1;
  FlightData data;
  data.source = "synthetic:" + model.name;
  std::vector<double> t(n);
  std::vector<std::string> names{"p", "v", "phi", "delta_f", "delta_t", "phi_sp"};
  if (lat4) names.push_back("r");
  std::map<std::string, std::vector<double>> rec;
  for (const auto& name : names) rec[name].resize(n);

  Eigen::VectorXd z = Eigen::VectorXd::Zero(nz);
  Eigen::VectorXd c = Eigen::VectorXd::Zero(nc);
  for (std::size_t k = 0; k < n; ++k) {
    const double tk = static_cast<double>(k) * dt;
    t[k] = tk;
    const double sp = doublet_train_rad(o, tk);
    rec["p"][k] = z[ip] + noise(o.noise_p_radps);
    if (lat4) rec["r"][k] = z[ir] + noise(o.noise_p_radps);
    rec["v"][k] = z[iv] + noise(o.noise_v_mps);
    rec["phi"][k] = z[iphi] + noise(o.noise_phi_rad);
    rec["delta_f"][k] = z[nx] + noise(o.noise_delta_f_radps);
    rec["delta_t"][k] = z[nx + 1] + noise(o.noise_delta_t_pct);
    rec["phi_sp"][k] = sp;
    // The controller acts on the true state: the feedback loop is not what is identified.
    c[0] = o.k_phi_radps_per_rad * (sp - z[iphi]) - o.k_p_radps_per_radps * z[ip];
    c[1] = i_t >= 0 ? throttle_pct(o, tk) : 0.0;
    c[2] = noise(o.moment_noise_Nm);
    if (lat4) c[3] = noise(o.moment_noise_Nm);
    c[2 + nw - 1] = noise(o.force_noise_N);
    z = d.Ad * z + d.Bd * c;
  }
  for (const auto& name : names) data.channels[name] = Channel{t, rec[name]};
  return data;
}

}  // namespace nimble::ident
