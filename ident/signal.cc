#include "ident/signal.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

namespace nimble::ident {

const Eigen::VectorXd& UniformData::at(const std::string& name) const {
  const auto it = signals.find(name);
  if (it == signals.end()) throw std::out_of_range(source + ": no signal '" + name + "'");
  return it->second;
}

namespace {

/// Slopes of the cubic Hermite interpolant of (t, y) at every sample (see Interpolation::kCubic).
std::vector<double> hermite_slopes(const std::vector<double>& t, const std::vector<double>& y) {
  const std::size_t n = t.size();
  std::vector<double> m(n, 0.0);
  if (n < 2) return m;
  if (n == 2) {
    m[0] = m[1] = (y[1] - y[0]) / (t[1] - t[0]);
    return m;
  }
  for (std::size_t i = 1; i + 1 < n; ++i) {
    const double h0 = t[i] - t[i - 1], h1 = t[i + 1] - t[i];
    const double d0 = (y[i] - y[i - 1]) / h0, d1 = (y[i + 1] - y[i]) / h1;
    m[i] = (h1 * d0 + h0 * d1) / (h0 + h1);
  }
  {
    const double h0 = t[1] - t[0], h1 = t[2] - t[1];
    const double d0 = (y[1] - y[0]) / h0, d1 = (y[2] - y[1]) / h1;
    m[0] = ((2.0 * h0 + h1) * d0 - h0 * d1) / (h0 + h1);
  }
  {
    const double h0 = t[n - 2] - t[n - 3], h1 = t[n - 1] - t[n - 2];
    const double d0 = (y[n - 2] - y[n - 3]) / h0, d1 = (y[n - 1] - y[n - 2]) / h1;
    m[n - 1] = ((2.0 * h1 + h0) * d1 - h1 * d0) / (h0 + h1);
  }
  return m;
}

}  // namespace

bool is_set_point(const std::string& channel) { return channel == "phi_sp"; }

std::string to_string(Interpolation interpolation) {
  return interpolation == Interpolation::kLinear ? "linear" : "cubic";
}

Interpolation interpolation_from_string(const std::string& name) {
  if (name == "linear") return Interpolation::kLinear;
  if (name == "cubic") return Interpolation::kCubic;
  throw std::invalid_argument("interpolation must be linear or cubic, got '" + name + "'");
}

UniformData resample_uniform(const FlightData& data, double rate_hz, Interpolation interpolation) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("resample rate must be positive and finite, got " + std::to_string(rate_hz));
  }
  if (data.channels.empty()) throw std::invalid_argument(data.source + ": no channels to resample");
  validate_flight_data(data);
  double t0 = -INFINITY, t1 = INFINITY;
  for (const auto& [name, c] : data.channels) {
    if (c.t_s.empty()) throw std::invalid_argument(data.source + ": channel '" + name + "' is empty");
    t0 = std::max(t0, c.t_s.front());
    t1 = std::min(t1, c.t_s.back());
  }
  const double dt = 1.0 / rate_hz;
  // Tolerance of a millionth of a step so that a grid that lands on the last
  // stamp up to rounding keeps its last point.
  const double span = (t1 - t0) / dt;
  const Eigen::Index n = span < 0.0 ? 0 : static_cast<Eigen::Index>(std::floor(span + 1e-6)) + 1;
  if (n < 2) {
    throw std::invalid_argument(data.source + ": the channels overlap for less than two samples at " +
                                std::to_string(rate_hz) + " Hz");
  }
  UniformData out;
  out.source = data.source;
  out.rate_hz = rate_hz;
  out.t_s.resize(n);
  for (Eigen::Index k = 0; k < n; ++k) out.t_s[k] = t0 + static_cast<double>(k) * dt;
  for (const auto& [name, c] : data.channels) {
    Eigen::VectorXd y(n);
    // Set-points are steps, not band-limited signals: linear, which never overshoots.
    const bool cubic = interpolation == Interpolation::kCubic && c.t_s.size() >= 3 && !is_set_point(name);
    const std::vector<double> slope = cubic ? hermite_slopes(c.t_s, c.values) : std::vector<double>{};
    std::size_t j = 0;  // c.t_s[j] <= t < c.t_s[j + 1]
    for (Eigen::Index k = 0; k < n; ++k) {
      const double t = std::min(out.t_s[k], c.t_s.back());
      while (j + 2 < c.t_s.size() && c.t_s[j + 1] <= t) ++j;
      if (c.t_s.size() == 1) {
        y[k] = c.values[0];
        continue;
      }
      const double ta = c.t_s[j], tb = c.t_s[j + 1];
      const double a = std::clamp((t - ta) / (tb - ta), 0.0, 1.0);
      if (!cubic) {
        y[k] = (1.0 - a) * c.values[j] + a * c.values[j + 1];
        continue;
      }
      const double h = tb - ta, a2 = a * a, a3 = a2 * a;
      y[k] = (2.0 * a3 - 3.0 * a2 + 1.0) * c.values[j] + (a3 - 2.0 * a2 + a) * h * slope[j] +
             (3.0 * a2 - 2.0 * a3) * c.values[j + 1] + (a3 - a2) * h * slope[j + 1];
    }
    out.signals.emplace(name, std::move(y));
  }
  return out;
}

std::vector<SecondOrderSection> butterworth_lowpass(int order, double cutoff_hz, double rate_hz) {
  if (order < 1 || order > 40) {
    throw std::invalid_argument("Butterworth order must be in [1, 40], got " + std::to_string(order));
  }
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("sample rate must be positive and finite, got " + std::to_string(rate_hz));
  }
  if (!(cutoff_hz > 0.0) || !(cutoff_hz < rate_hz / 2.0)) {
    throw std::invalid_argument("cut-off must be in (0, " + std::to_string(rate_hz / 2.0) +
                                ") Hz (below Nyquist), got " + std::to_string(cutoff_hz));
  }
  const double fs2 = 2.0 * rate_hz;
  const double wa = fs2 * std::tan(M_PI * cutoff_hz / rate_hz);  // pre-warped analog cut-off [rad/s]
  std::vector<SecondOrderSection> sos;
  // Analog poles wa * exp(j pi (2k + N + 1) / (2N)), k = 0..N-1, all in the left half plane;
  // one of each conjugate pair (imag > 0) and the real pole of an odd order.
  for (int k = 0; k < order; ++k) {
    const std::complex<double> s = wa * std::polar(1.0, M_PI * (2.0 * k + order + 1.0) / (2.0 * order));
    if (s.imag() < -1e-12 * wa) continue;
    const std::complex<double> z = (fs2 + s) / (fs2 - s);  // bilinear transform
    SecondOrderSection sec;
    if (std::fabs(s.imag()) <= 1e-12 * wa) {
      sec.a1 = -z.real();
      sec.a2 = 0.0;
      const double gain = (1.0 + sec.a1) / 2.0;  // unity at DC; zero at z = -1
      sec.b0 = gain;
      sec.b1 = gain;
      sec.b2 = 0.0;
    } else {
      sec.a1 = -2.0 * z.real();
      sec.a2 = std::norm(z);
      const double gain = (1.0 + sec.a1 + sec.a2) / 4.0;  // unity at DC; double zero at z = -1
      sec.b0 = gain;
      sec.b1 = 2.0 * gain;
      sec.b2 = gain;
    }
    sos.push_back(sec);
  }
  // Least resonant sections first; the first-order section (a2 = 0) last.
  std::stable_sort(sos.begin(), sos.end(), [](const SecondOrderSection& a, const SecondOrderSection& b) {
    if ((a.a2 == 0.0) != (b.a2 == 0.0)) return b.a2 == 0.0;
    return a.a2 < b.a2;
  });
  return sos;
}

std::complex<double> frequency_response(const std::vector<SecondOrderSection>& sos, double f_hz, double rate_hz) {
  const std::complex<double> zi = std::polar(1.0, -2.0 * M_PI * f_hz / rate_hz);  // z^-1
  std::complex<double> h = 1.0;
  for (const auto& s : sos) {
    h *= (s.b0 + s.b1 * zi + s.b2 * zi * zi) / (1.0 + s.a1 * zi + s.a2 * zi * zi);
  }
  return h;
}

double butterworth_magnitude_squared(int order, double cutoff_hz, double rate_hz, double f_hz) {
  const double ratio = std::tan(M_PI * f_hz / rate_hz) / std::tan(M_PI * cutoff_hz / rate_hz);
  return 1.0 / (1.0 + std::pow(ratio * ratio, order));
}

Eigen::VectorXd sosfilt(const std::vector<SecondOrderSection>& sos, const Eigen::VectorXd& x, bool steady_start) {
  Eigen::VectorXd y = x;
  for (const auto& s : sos) {
    // Direct form II transposed. Steady state for a constant input c with unity
    // DC gain: z2 = (b2 - a2) c, z1 = (b1 - a1) c + z2.
    double z1 = 0.0, z2 = 0.0;
    if (steady_start && y.size() > 0) {
      const double dc = s.b0 + s.b1 + s.b2;
      const double c = y[0] * dc / (1.0 + s.a1 + s.a2);  // output level for input y[0]
      z2 = s.b2 * y[0] - s.a2 * c;
      z1 = s.b1 * y[0] - s.a1 * c + z2;
    }
    for (Eigen::Index k = 0; k < y.size(); ++k) {
      const double in = y[k];
      const double out = s.b0 * in + z1;
      z1 = s.b1 * in - s.a1 * out + z2;
      z2 = s.b2 * in - s.a2 * out;
      y[k] = out;
    }
  }
  return y;
}

std::size_t default_padding(double cutoff_hz, double rate_hz) {
  return static_cast<std::size_t>(std::ceil(6.0 * rate_hz / cutoff_hz));
}

Eigen::VectorXd filtfilt(const std::vector<SecondOrderSection>& sos, const Eigen::VectorXd& x, std::size_t padding) {
  const Eigen::Index n = x.size();
  if (n < 2) throw std::invalid_argument("filtfilt needs at least 2 samples, got " + std::to_string(n));
  const Eigen::Index pad = std::min<Eigen::Index>(static_cast<Eigen::Index>(padding), n - 1);
  Eigen::VectorXd ext(n + 2 * pad);
  for (Eigen::Index k = 0; k < pad; ++k) {
    ext[k] = 2.0 * x[0] - x[pad - k];
    ext[n + pad + k] = 2.0 * x[n - 1] - x[n - 2 - k];
  }
  ext.segment(pad, n) = x;
  Eigen::VectorXd y = sosfilt(sos, ext, true);
  y.reverseInPlace();
  y = sosfilt(sos, y, true);
  y.reverseInPlace();
  return y.segment(pad, n);
}

Eigen::VectorXd differentiate(const Eigen::VectorXd& x, double rate_hz) {
  if (!(rate_hz > 0.0) || !std::isfinite(rate_hz)) {
    throw std::invalid_argument("differentiate: rate must be positive and finite");
  }
  const Eigen::Index n = x.size();
  if (n < 2) throw std::invalid_argument("differentiate needs at least 2 samples");
  Eigen::VectorXd d(n);
  if (n == 2) {
    d.setConstant((x[1] - x[0]) * rate_hz);
    return d;
  }
  const double half_rate = 0.5 * rate_hz;
  const double twelfth_rate = rate_hz / 12.0;
  for (Eigen::Index k = 2; k + 2 < n; ++k) {
    d[k] = (x[k - 2] - 8.0 * x[k - 1] + 8.0 * x[k + 1] - x[k + 2]) * twelfth_rate;
  }
  for (const Eigen::Index k : {Eigen::Index{1}, n - 2}) {
    if (k >= 1 && k + 1 < n) d[k] = (x[k + 1] - x[k - 1]) * half_rate;
  }
  d[0] = (-3.0 * x[0] + 4.0 * x[1] - x[2]) * half_rate;
  d[n - 1] = (3.0 * x[n - 1] - 4.0 * x[n - 2] + x[n - 3]) * half_rate;
  return d;
}

UniformData lowpass_filtered(UniformData u, const ProcessingOptions& options) {
  if (options.filter_order == 0) return u;
  const auto sos = butterworth_lowpass(options.filter_order, options.cutoff_hz, options.rate_hz);
  const std::size_t pad = options.padding ? options.padding : default_padding(options.cutoff_hz, options.rate_hz);
  for (auto& [name, y] : u.signals) y = filtfilt(sos, y, pad);
  return u;
}

UniformData process(const FlightData& data, const ProcessingOptions& options) {
  return lowpass_filtered(resample_uniform(data, options.rate_hz, options.interpolation), options);
}

}  // namespace nimble::ident
