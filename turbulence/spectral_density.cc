#include "turbulence/spectral_density.h"

#include <cmath>
#include <complex>
#include <stdexcept>
#include <string>

namespace nimble::turbulence {
namespace {

void check_intensity(const LinearSystem& sys, const Eigen::VectorXd& intensity) {
  if (intensity.size() != sys.n_inputs()) {
    throw std::invalid_argument("output_psd: " + std::to_string(intensity.size()) + " intensities for " +
                                std::to_string(sys.n_inputs()) + " inputs");
  }
  if ((intensity.array() < 0.0).any()) throw std::invalid_argument("output_psd: a white-noise intensity is negative");
}

/// 5-point Gauss-Legendre nodes and weights on [-1, 1].
constexpr double kNodes[5] = {-0.9061798459386640, -0.5384693101056831, 0.0, 0.5384693101056831, 0.9061798459386640};
constexpr double kWeights[5] = {0.2369268850561891, 0.4786286704993665, 0.5688888888888889, 0.4786286704993665,
                                0.2369268850561891};

Eigen::VectorXd gauss_panels(const std::function<Eigen::VectorXd(double)>& f, double a, double b, int panels) {
  const double h = (b - a) / panels;
  Eigen::VectorXd sum;
  for (int k = 0; k < panels; ++k) {
    const double mid = a + (k + 0.5) * h;
    for (int i = 0; i < 5; ++i) {
      const Eigen::VectorXd v = kWeights[i] * f(mid + 0.5 * h * kNodes[i]);
      if (sum.size() == 0) {
        sum = v;
      } else {
        sum += v;
      }
    }
  }
  return 0.5 * h * sum;
}

}  // namespace

Eigen::VectorXd output_psd(const LinearSystem& sys, const Eigen::VectorXd& intensity, double omega_radps) {
  check_intensity(sys, intensity);
  const Eigen::MatrixXcd H = frequency_response(sys, omega_radps);
  return H.cwiseAbs2() * intensity;
}

Eigen::MatrixXd output_psd(const LinearSystem& sys, const Eigen::VectorXd& intensity,
                           const Eigen::VectorXd& omega_radps) {
  Eigen::MatrixXd out(omega_radps.size(), sys.n_outputs());
  for (Eigen::Index k = 0; k < omega_radps.size(); ++k) {
    out.row(k) = output_psd(sys, intensity, omega_radps[k]).transpose();
  }
  return out;
}

Eigen::VectorXd coherent_output_psd(const LinearSystem& sys, const Eigen::VectorXd& intensity, double omega_radps) {
  check_intensity(sys, intensity);
  const Eigen::MatrixXcd H = frequency_response(sys, omega_radps);
  const Eigen::VectorXd amplitude = H.cwiseAbs() * intensity.cwiseSqrt();
  return amplitude.cwiseAbs2();
}

VectorQuadrature integrate_psds(const std::function<Eigen::VectorXd(double)>& psds, double omega_max_radps,
                                double omega_scale_radps, double rel_tol) {
  if (!(omega_max_radps > 0.0) || !(omega_scale_radps > 0.0)) {
    throw std::invalid_argument("integrate_psd: omega_max and omega_scale must be > 0");
  }
  const double c = omega_scale_radps;
  const double theta_max = std::isinf(omega_max_radps) ? 0.5 * M_PI : std::atan(omega_max_radps / c);
  // d omega = c sec^2(theta) d theta
  const auto integrand = [&](double theta) -> Eigen::VectorXd {
    const double cs = std::cos(theta);
    return psds(c * std::tan(theta)) * (c / (cs * cs));
  };
  VectorQuadrature q;
  q.panels = 64;
  Eigen::VectorXd previous = gauss_panels(integrand, 0.0, theta_max, q.panels);
  while (true) {
    const Eigen::VectorXd next = gauss_panels(integrand, 0.0, theta_max, 2 * q.panels);
    q.panels *= 2;
    q.error = (next - previous).cwiseAbs() / M_PI;
    q.value = next / M_PI;
    const bool converged = (q.error.array() <= rel_tol * q.value.array().abs()).all();
    if (converged || q.panels >= (1 << 16)) break;
    previous = next;
  }
  return q;
}

Quadrature integrate_psd(const std::function<double(double)>& psd, double omega_max_radps, double omega_scale_radps,
                         double rel_tol) {
  const VectorQuadrature v = integrate_psds([&](double w) { return Eigen::VectorXd::Constant(1, psd(w)); },
                                            omega_max_radps, omega_scale_radps, rel_tol);
  Quadrature q;
  q.value = v.value[0];
  q.error = v.error[0];
  q.panels = v.panels;
  return q;
}

Eigen::MatrixXd sampled_output_psd(const Eigen::MatrixXd& Phi, const Eigen::MatrixXd& P, const Eigen::MatrixXd& C,
                                   double dt_s, const Eigen::VectorXd& omega_radps) {
  const Eigen::MatrixXd R0 = C * P * C.transpose();
  const Eigen::MatrixXcd rhs = (Phi * P * C.transpose()).cast<std::complex<double>>();
  const Eigen::MatrixXcd Cc = C.cast<std::complex<double>>();
  const Eigen::MatrixXcd Phic = Phi.cast<std::complex<double>>();
  Eigen::MatrixXd out(omega_radps.size(), C.rows());
  for (Eigen::Index k = 0; k < omega_radps.size(); ++k) {
    const std::complex<double> z = std::polar(1.0, omega_radps[k] * dt_s);
    Eigen::MatrixXcd M = -Phic;
    M.diagonal().array() += z;
    const Eigen::MatrixXcd G = Cc * M.partialPivLu().solve(rhs);  // p x p; the diagonal is used
    for (Eigen::Index i = 0; i < C.rows(); ++i) out(k, i) = dt_s * (R0(i, i) + 2.0 * G(i, i).real());
  }
  return out;
}

}  // namespace nimble::turbulence
