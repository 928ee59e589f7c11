#include "core/modes.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace nimble {
namespace {

constexpr double kImagTol = 1e-9;

bool eigen_less(const std::complex<double>& a, const std::complex<double>& b) {
  if (std::fabs(a.real() - b.real()) > 1e-12 * (1.0 + std::fabs(a.real()))) return a.real() < b.real();
  return a.imag() > b.imag();
}

int reference_index(const StateSpace& ss) {
  for (std::size_t i = 0; i < ss.states.size(); ++i) {
    if (ss.states[i] == "phi" || ss.states[i] == "theta") return static_cast<int>(i);
  }
  return static_cast<int>(ss.states.size()) - 1;
}

}  // namespace

Eigen::VectorXd nondim_divisors(const StateSpace& ss, const Vehicle& vehicle) {
  const double f = vehicle.flap_frequency_radps();
  const double velocity_scale = 2.0 * vehicle.flap_amplitude_rad * f * vehicle.r2_m;
  Eigen::VectorXd div(ss.states.size());
  for (std::size_t i = 0; i < ss.states.size(); ++i) {
    const std::string& unit = ss.state_units[i];
    if (unit == "rad/s")
      div[i] = f;
    else if (unit == "m/s")
      div[i] = velocity_scale;
    else
      div[i] = 2.0 * M_PI;  // angles
  }
  return div;
}

std::vector<std::complex<double>> sorted_eigenvalues(const Eigen::MatrixXd& A) {
  Eigen::EigenSolver<Eigen::MatrixXd> solver(A, false);
  std::vector<std::complex<double>> out;
  for (Eigen::Index i = 0; i < solver.eigenvalues().size(); ++i) out.push_back(solver.eigenvalues()[i]);
  std::sort(out.begin(), out.end(), eigen_less);
  return out;
}

std::vector<Mode> analyse_modes(const StateSpace& ss, const Vehicle& vehicle) {
  Eigen::EigenSolver<Eigen::MatrixXd> solver(ss.A, true);
  const Eigen::VectorXd div = nondim_divisors(ss, vehicle);
  const int ref = reference_index(ss);

  std::vector<Mode> modes;
  for (Eigen::Index i = 0; i < solver.eigenvalues().size(); ++i) {
    const std::complex<double> lambda = solver.eigenvalues()[i];
    if (lambda.imag() < -kImagTol) continue;  // keep one member of each pair
    Mode mode;
    mode.eigenvalue = lambda;
    mode.oscillatory = lambda.imag() > kImagTol;
    mode.stable = lambda.real() < 0.0;
    mode.natural_frequency_radps = std::abs(lambda);
    mode.damping_ratio = mode.natural_frequency_radps > 0.0 ? -lambda.real() / mode.natural_frequency_radps : 0.0;
    mode.period_s = mode.oscillatory ? 2.0 * M_PI / lambda.imag() : 0.0;
    mode.time_to_double_or_half_s =
        lambda.real() != 0.0 ? std::log(2.0) / std::fabs(lambda.real()) : std::numeric_limits<double>::infinity();
    Eigen::VectorXcd vec = solver.eigenvectors().col(i);
    for (Eigen::Index k = 0; k < vec.size(); ++k) vec[k] /= div[k];
    if (std::abs(vec[ref]) > 0.0) vec /= vec[ref];
    mode.eigenvector_nondim = vec;
    modes.push_back(mode);
  }
  std::sort(modes.begin(), modes.end(),
            [](const Mode& a, const Mode& b) { return eigen_less(a.eigenvalue, b.eigenvalue); });
  return modes;
}

}  // namespace nimble
