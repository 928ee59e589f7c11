#include "controller/loop_margins.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <stdexcept>
#include <string>

#include <Eigen/Eigenvalues>

#include "core/constants.h"

namespace nimble {
namespace {

constexpr double kInf = std::numeric_limits<double>::infinity();
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

/// Phase in (-180, 180] [deg].
double wrap_deg(double deg) {
  double x = std::fmod(deg, 360.0);
  if (x <= -180.0) x += 360.0;
  if (x > 180.0) x -= 360.0;
  return x;
}

/// A point where L is real and negative: the closed loop with gain k = -1/L is on its boundary.
struct GainCandidate {
  double k;
  double omega;
};

/// The nearest candidate beyond 1 (upward or downward) at which stability really changes.
std::optional<GainCandidate> stability_edge(const BrokenLoop& loop, std::vector<GainCandidate> candidates,
                                            bool upward) {
  std::sort(candidates.begin(), candidates.end(),
            [upward](const GainCandidate& a, const GainCandidate& b) { return upward ? a.k < b.k : a.k > b.k; });
  for (std::size_t i = 0; i < candidates.size(); ++i) {
    const double k = candidates[i].k;
    double probe = upward ? k * 1.001 : k * 0.999;
    if (i + 1 < candidates.size()) {
      const double next = candidates[i + 1].k;
      probe = next > 0.0 ? std::sqrt(k * next) : 0.5 * k;
    }
    if (!schur_stable(closed_loop_matrix(loop, probe))) return candidates[i];
  }
  return std::nullopt;
}

}  // namespace

LoopResponse::LoopResponse(const BrokenLoop& loop) {
  const Eigen::Index n = loop.A.rows();
  if (loop.A.cols() != n || loop.B.size() != n || loop.C.size() != n || n == 0) {
    throw std::invalid_argument("loop response: A must be square and B, C of its size");
  }
  if (!(std::isfinite(loop.dt_s) && loop.dt_s > 0.0)) {
    throw std::invalid_argument("loop response: dt_s must be > 0, got " + std::to_string(loop.dt_s));
  }
  Eigen::HessenbergDecomposition<Eigen::MatrixXd> hess(loop.A);
  const Eigen::MatrixXd Q = hess.matrixQ();
  H_ = hess.matrixH();
  QtB_ = Q.transpose() * loop.B;
  CQ_ = loop.C * Q;
  D_ = loop.D;
  dt_s_ = loop.dt_s;
  nyquist_radps_ = kPi / loop.dt_s;
}

std::complex<double> LoopResponse::open(double omega_radps) const {
  using C = std::complex<double>;
  const Eigen::Index n = H_.rows();
  const C z = std::polar(1.0, omega_radps * dt_s_);
  // (zI - H) x = Q^T B by Gaussian elimination with partial pivoting between neighbouring rows:
  // an upper Hessenberg matrix has one element below its diagonal per column.
  Eigen::MatrixXcd M = -H_.cast<C>();
  M.diagonal().array() += z;
  Eigen::VectorXcd b = QtB_.cast<C>();
  for (Eigen::Index k = 0; k + 1 < n; ++k) {
    if (std::abs(M(k + 1, k)) > std::abs(M(k, k))) {
      M.row(k).segment(k, n - k).swap(M.row(k + 1).segment(k, n - k));
      std::swap(b(k), b(k + 1));
    }
    if (M(k, k) == C(0.0)) continue;
    const C l = M(k + 1, k) / M(k, k);
    M.row(k + 1).segment(k, n - k) -= l * M.row(k).segment(k, n - k);
    b(k + 1) -= l * b(k);
  }
  for (Eigen::Index k = n - 1; k >= 0; --k) {
    C s = b(k);
    for (Eigen::Index j = k + 1; j < n; ++j) s -= M(k, j) * b(j);
    if (M(k, k) == C(0.0)) return C(kInf, 0.0);
    b(k) = s / M(k, k);
  }
  return (CQ_.cast<C>() * b)(0) + D_;
}

double bisect_sign_change(const std::function<double(double)>& f, double a, double b) {
  double fa = f(a);
  for (int i = 0; i < 80 && (b - a) > 1e-9 * b; ++i) {
    const double m = 0.5 * (a + b);
    const double fm = f(m);
    if ((fm < 0.0) == (fa < 0.0)) {
      a = m;
      fa = fm;
    } else {
      b = m;
    }
  }
  return 0.5 * (a + b);
}

double LoopMargins::gain_margin_db() const { return 20.0 * std::log10(gain_margin); }

double LoopMargins::gain_reduction_margin_db() const {
  return gain_reduction_margin > 0.0 ? 20.0 * std::log10(gain_reduction_margin) : -kInf;
}

Eigen::MatrixXd closed_loop_matrix(const BrokenLoop& loop, double k) {
  const double denom = 1.0 - k * loop.D;
  if (denom == 0.0) throw std::invalid_argument("closed loop: k D = 1, the loop has no solution");
  return loop.A + (k / denom) * loop.B * loop.C;
}

bool schur_stable(const Eigen::MatrixXd& phi) {
  const Eigen::VectorXcd eig = phi.eigenvalues();
  for (Eigen::Index i = 0; i < eig.size(); ++i) {
    if (!(std::abs(eig(i)) < 1.0)) return false;
  }
  return true;
}

LoopMargins loop_margins(const BrokenLoop& loop, const MarginOptions& options) {
  const LoopResponse response(loop);
  const double nyquist = response.nyquist_radps();
  const double w_min = 2.0 * kPi * options.f_min_hz;
  if (!(options.grid_points >= 10 && w_min > 0.0 && w_min < nyquist)) {
    throw std::invalid_argument("loop margins: need at least 10 grid points and 0 < f_min below Nyquist");
  }
  LoopMargins m;
  m.open_loop_stable = schur_stable(loop.A);
  m.closed_loop_stable = schur_stable(closed_loop_matrix(loop));

  const int n = options.grid_points;
  std::vector<double> w(static_cast<std::size_t>(n));
  std::vector<std::complex<double>> L(w.size());
  for (int i = 0; i < n; ++i) {
    w[static_cast<std::size_t>(i)] = w_min * std::pow(nyquist / w_min, static_cast<double>(i) / (n - 1));
    L[static_cast<std::size_t>(i)] = response.ratio(w[static_cast<std::size_t>(i)]);
  }
  auto log_gain = [&](double x) { return std::log(std::abs(response.ratio(x))); };
  auto imag = [&](double x) { return response.ratio(x).imag(); };

  std::vector<GainCandidate> candidates;
  // z = 1 and z = -1: L is real there.
  for (const double x : {0.0, nyquist}) {
    const std::complex<double> l = response.ratio(x);
    if (std::isfinite(l.real()) && l.real() < 0.0) candidates.push_back({-1.0 / l.real(), x});
  }
  double best_abs_pm = kInf;
  for (std::size_t i = 0; i + 1 < w.size(); ++i) {
    const std::complex<double> a = L[i], b = L[i + 1];
    if (!(std::isfinite(std::abs(a)) && std::isfinite(std::abs(b)))) continue;
    // Phase crossover: L crosses the real axis on its negative side.
    if ((a.imag() < 0.0) != (b.imag() < 0.0)) {
      const double x = bisect_sign_change(imag, w[i], w[i + 1]);
      const std::complex<double> l = response.ratio(x);
      if (l.real() < 0.0 && std::abs(l.imag()) < 1e-6 * std::abs(l) + 1e-12) candidates.push_back({-1.0 / l.real(), x});
    }
    // Gain crossover.
    if ((std::abs(a) < 1.0) != (std::abs(b) < 1.0)) {
      const double x = bisect_sign_change(log_gain, w[i], w[i + 1]);
      const double pm = wrap_deg(180.0 + std::arg(response.ratio(x)) * 180.0 / kPi);
      m.crossovers_hz.push_back(x / (2.0 * kPi));
      if (std::abs(pm) < best_abs_pm) {
        best_abs_pm = std::abs(pm);
        m.phase_margin_deg = pm;
        m.crossover_hz = x / (2.0 * kPi);
      }
      const double lag_deg = pm > 0.0 ? pm : pm + 360.0;
      m.delay_margin_s = std::min(m.delay_margin_s, lag_deg * kPi / 180.0 / x);
    }
  }

  // Peak sensitivity: the grid's largest |S|, refined by golden section between its neighbours.
  auto sens = [&](double x) { return 1.0 / std::abs(1.0 + response.ratio(x)); };
  std::size_t peak = 0;
  for (std::size_t i = 0; i < w.size(); ++i) {
    if (1.0 / std::abs(1.0 + L[i]) > 1.0 / std::abs(1.0 + L[peak])) peak = i;
  }
  double lo = w[peak == 0 ? 0 : peak - 1], hi = w[std::min(peak + 1, w.size() - 1)];
  const double g = 0.5 * (std::sqrt(5.0) - 1.0);
  for (int it = 0; it < 60 && hi - lo > 1e-9 * hi; ++it) {
    const double x1 = hi - g * (hi - lo), x2 = lo + g * (hi - lo);
    if (sens(x1) > sens(x2)) {
      hi = x2;
    } else {
      lo = x1;
    }
  }
  m.sensitivity_peak_hz = 0.5 * (lo + hi) / (2.0 * kPi);
  m.sensitivity_peak = std::max(sens(0.5 * (lo + hi)), 1.0 / std::abs(1.0 + L[peak]));

  if (!m.closed_loop_stable) {
    // A loop that is already unstable has no margins to state.
    m.gain_margin = m.gain_reduction_margin = kNaN;
    m.delay_margin_s = 0.0;
    return m;
  }
  std::vector<GainCandidate> above, below;
  for (const GainCandidate& c : candidates) (c.k > 1.0 ? above : below).push_back(c);
  if (const auto up = stability_edge(loop, above, true)) {
    m.gain_margin = up->k;
    m.gain_margin_hz = up->omega / (2.0 * kPi);
  }
  if (const auto down = stability_edge(loop, below, false)) {
    m.gain_reduction_margin = down->k;
    m.gain_reduction_margin_hz = down->omega / (2.0 * kPi);
  }
  return m;
}

std::vector<LoopPole> loop_poles(const Eigen::MatrixXd& phi, double dt_s, int* at_origin, double origin_tol) {
  const Eigen::VectorXcd eig = phi.eigenvalues();
  std::vector<LoopPole> poles;
  int origin = 0;
  for (Eigen::Index i = 0; i < eig.size(); ++i) {
    LoopPole p;
    p.z = eig(i);
    if (std::abs(p.z) < origin_tol) {
      ++origin;
      continue;
    }
    p.s = std::log(p.z) / dt_s;
    const double mag = std::abs(p.s);
    p.natural_hz = mag / (2.0 * kPi);
    p.damping = mag > 0.0 ? -p.s.real() / mag : 1.0;
    poles.push_back(p);
  }
  std::sort(poles.begin(), poles.end(), [](const LoopPole& a, const LoopPole& b) {
    return a.s.real() != b.s.real() ? a.s.real() > b.s.real() : a.s.imag() > b.s.imag();
  });
  if (at_origin) *at_origin = origin;
  return poles;
}

}  // namespace nimble
