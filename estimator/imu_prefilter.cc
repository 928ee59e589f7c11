#include "estimator/imu_prefilter.h"

#include <algorithm>
#include <climits>
#include <cmath>
#include <stdexcept>
#include <tuple>

namespace nimble {

const ParamTable<ImuPrefilterConfig>& imu_prefilter_params() {
  using C = ImuPrefilterConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "the on-board IMU filtering before the EKF on or off"},
      {"flap_harmonics", &C::flap_harmonics, Range::closed(0, 8), "-",
       "lines at k x each wing pair's measured flapping frequency (ACTUATOR_FB), k = 1..this"},
      {"flap_notch_bandwidth_hz", &C::flap_notch_bandwidth_hz, Range::closed(0.1, 20.0), "Hz",
       "-3 dB width of each flapping line's notch; assumption: a few Hz, the lines' amplitudes change slowly"},
      {"initial_flap_freq_hz", &C::initial_flap_freq_hz, Range::closed(0.0, 40.0), "Hz",
       "flapping frequency before the first actuator feedback; thesis: 17 Hz"},
      {"structural_notch_hz", &C::structural_notch_hz, Range::closed(0.0, 100.0), "Hz",
       "fixed line (0: none); thesis Section 8.3: the yaw-rate line at about 11 Hz"},
      {"structural_notch_bandwidth_hz", &C::structural_notch_bandwidth_hz, Range::closed(0.1, 20.0), "Hz",
       "-3 dB width of the fixed line's notch"},
      {"structural_notch_p", &C::structural_notch_p, Range::any(), "-", "the fixed line on the roll rate"},
      {"structural_notch_q", &C::structural_notch_q, Range::any(), "-", "the fixed line on the pitch rate"},
      {"structural_notch_r", &C::structural_notch_r, Range::any(), "-",
       "the fixed line on the yaw rate; thesis Section 8.3: the 11 Hz line is the yaw rate's"},
      {"structural_notch_accel", &C::structural_notch_accel, Range::any(), "-",
       "the fixed line on the accelerometer channels"},
      {"accel", &C::accel, Range::any(), "-", "the flapping lines on the accelerometer channels too"},
      {"level_bandwidth_hz", &C::level_bandwidth_hz, Range::closed(1.0, 100.0), "Hz",
       "bandwidth of the level that takes the motion, so the lines learn from what it leaves; above the manoeuvres' 7 "
       "Hz"},
      {"amplitude_smoothing_s", &C::amplitude_smoothing_s, Range::closed(0.0, 1.0), "s",
       "low-pass of the amplitudes the output uses (0: none): smooths away what the motion shakes into them"},
  };
  return table;
}

ImuPrefilter::ImuPrefilter(const ImuPrefilterConfig& config, double sample_rate_hz)
    : config_(config), fs_(sample_rate_hz) {
  try {
    check_params(imu_prefilter_params(), config_);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("ImuPrefilterConfig.") + e.what());
  }
  if (!(fs_ > 0.0) || !std::isfinite(fs_)) throw std::invalid_argument("ImuPrefilter: sample rate must be positive");
  const double w0 = 2.0 * M_PI * config_.initial_flap_freq_hz;
  feedback_[0] = feedback_[1] = {INT64_MIN, w0, w0};
  const int n_flap = 2 * config_.flap_harmonics;
  lines_.resize(static_cast<std::size_t>(n_flap) + 1);
  // A line element's random walk alpha = rho wB^2 dt dt_nom / 2 gives it the steady gain wB dt
  // (a notch of width B); the level's, alpha = k^2 rho / (1 - k) per nominal sample, the steady
  // gain k = 2 pi B_level / fs.
  const double dt_nom = 1.0 / fs_;
  const double k = std::min(0.5, 2.0 * M_PI * config_.level_bandwidth_hz / fs_);
  // Each channel's lines; channels of one sensor with the same lines share a set (rho, measured
  // per set, differs between the gyro and the accelerometer by two orders of magnitude).
  const bool structural_on[6] = {config_.structural_notch_p,     config_.structural_notch_q,
                                 config_.structural_notch_r,     config_.structural_notch_accel,
                                 config_.structural_notch_accel, config_.structural_notch_accel};
  for (int ch = 0; ch < 6; ++ch) {
    std::vector<int> lines;
    if (ch < 3 || config_.accel) {
      for (int i = 0; i < n_flap; ++i) lines.push_back(i);
    }
    if (structural_on[ch] && config_.structural_notch_hz > 0.0) lines.push_back(n_flap);
    auto it = std::find_if(sets_.begin(), sets_.end(),
                           [&](const LineSet& s) { return s.lines == lines && (s.channels.front() < 3) == (ch < 3); });
    if (it == sets_.end()) {
      LineSet set;
      set.lines = lines;
      const int d = 2 * static_cast<int>(lines.size());
      set.P = Eigen::MatrixXd::Identity(d + 1, d + 1);
      set.P(d, d) = kLevelPrior;
      set.alpha_rate.resize(d + 1);
      for (int e = 0; e < d; ++e) {
        const bool fixed = lines[static_cast<std::size_t>(e / 2)] == n_flap;
        const double wb =
            2.0 * M_PI * (fixed ? config_.structural_notch_bandwidth_hz : config_.flap_notch_bandwidth_hz);
        set.alpha_rate[e] = 0.5 * wb * wb * dt_nom;  // times rho at each step
      }
      set.alpha_rate[d] = k * k / (1.0 - k) * fs_;  // times rho at each step
      sets_.push_back(set);
      it = sets_.end() - 1;
    }
    it->channels.push_back(ch);
    amp_[ch] = Eigen::VectorXd::Zero(it->P.rows());
  }
  smooth_ = amp_;
}

void ImuPrefilter::set_flap_frequencies(double left_radps, double right_radps, std::int64_t utime) {
  if (!std::isfinite(left_radps) || !std::isfinite(right_radps)) return;
  if (utime <= feedback_[1].utime) {
    if (utime == feedback_[1].utime) feedback_[1] = {utime, left_radps, right_radps};
    return;
  }
  feedback_[0] = feedback_[1];
  feedback_[1] = {utime, left_radps, right_radps};
}

double ImuPrefilter::flap_radps(bool left, std::int64_t utime) const {
  const Feedback& a = feedback_[0];
  const Feedback& b = feedback_[1];
  const double fb = left ? b.left : b.right;
  if (a.utime == INT64_MIN || b.utime == INT64_MIN || b.utime <= a.utime) return fb;
  // On from the newest measurement along the last two, for at most two of their intervals (and
  // back at most one: in real time a sample may be older than the newest feedback).
  const double span = static_cast<double>(b.utime - a.utime);
  const double ahead = std::clamp(static_cast<double>(utime - b.utime), -span, 2.0 * span);
  return std::max(0.0, fb + (fb - (left ? a.left : a.right)) * ahead / span);
}

void ImuPrefilter::advance_lines(std::int64_t utime, double dt_s) {
  const double left = flap_radps(true, utime), right = flap_radps(false, utime);
  const std::size_t n_flap = lines_.size() - 1;
  for (std::size_t i = 0; i < lines_.size(); ++i) {
    const int k = static_cast<int>(i / 2) + 1;
    const double f_hz = i == n_flap ? config_.structural_notch_hz : k * (i % 2 == 0 ? left : right) / (2.0 * M_PI);
    Line& l = lines_[i];
    l.w = 0.0;  // left out
    if (f_hz > 0.0 && f_hz < 0.45 * fs_) l.w = 2.0 * M_PI * f_hz;
    l.theta = std::fmod(l.theta + l.w * dt_s, 2.0 * M_PI);
    l.ref = {std::cos(l.theta), std::sin(l.theta)};
  }
}

ImuSample ImuPrefilter::filter(const ImuSample& raw, std::int64_t rig_utime) {
  if (!config_.enabled) return raw;
  const std::array<double, 6> in{raw.gyro_radps.x(), raw.gyro_radps.y(), raw.gyro_radps.z(),
                                 raw.accel_mps2.x(), raw.accel_mps2.y(), raw.accel_mps2.z()};
  if (!started_) {
    first_utime_ = last_utime_ = raw.utime;
    started_ = true;
  }
  const std::int64_t dt_us = raw.utime - last_utime_;
  const double dt_s = 1e-6 * static_cast<double>(std::max<std::int64_t>(dt_us, 0));
  last_utime_ = std::max(last_utime_, raw.utime);
  advance_lines(rig_utime, dt_s);
  std::array<double, 6> filtered = in;
  for (LineSet& set : sets_) step_set(set, in, dt_s, &filtered);
  ImuSample out = raw;
  out.gyro_radps = Eigen::Vector3d(filtered[0], filtered[1], filtered[2]);
  out.accel_mps2 = Eigen::Vector3d(filtered[3], filtered[4], filtered[5]);
  return out;
}

void ImuPrefilter::step_set(LineSet& set, const std::array<double, 6>& in, double dt_s, std::array<double, 6>* out) {
  const int d = static_cast<int>(set.P.rows()) - 1;  // amplitude elements; the last is the level
  // The regressor: line i = a_i cos theta_i - b_i sin theta_i (a line left out: zero), level 1.
  Eigen::VectorXd h(d + 1);
  for (int e = 0; e < d; e += 2) {
    const Line& l = lines_[static_cast<std::size_t>(set.lines[static_cast<std::size_t>(e / 2)])];
    h[e] = l.w > 0.0 ? l.ref.real() : 0.0;
    h[e + 1] = l.w > 0.0 ? -l.ref.imag() : 0.0;
  }
  h[d] = 1.0;
  // The amplitudes wander and fall back to their prior I where nothing is learnt about them
  // (P <- D P D + diag(alpha), D = diag(sqrt(1 - alpha))); the level is a random walk. The
  // walks scale with rho, so that the steady gains (each notch's width, the level's bandwidth)
  // do not depend on it.
  const Eigen::VectorXd alpha = (set.alpha_rate * (dt_s * set.rho)).cwiseMin(1.0);
  Eigen::VectorXd shrink = (1.0 - alpha.array()).sqrt().matrix();
  shrink[d] = 1.0;
  set.P = shrink.asDiagonal() * set.P * shrink.asDiagonal();
  set.P.diagonal() += alpha;
  const Eigen::VectorXd Ph = set.P * h;
  const double s = h.dot(Ph) + set.rho;
  const Eigen::VectorXd K = Ph / s;
  const auto hl = h.head(d);
  const double smooth = config_.amplitude_smoothing_s > 0.0 ? -std::expm1(-dt_s / config_.amplitude_smoothing_s) : 1.0;
  const double noise_gain = -std::expm1(-dt_s / kNoiseTimeS);
  const double usual_gain = -std::expm1(-dt_s / kUsualTimeS);
  const int n_flap = 2 * config_.flap_harmonics;
  double noise = 0.0, power = 0.0;
  Eigen::VectorXd sh(d);
  for (const int ch : set.channels) {
    Eigen::VectorXd& x = amp_[ch];
    const double nu = in[ch] - h.dot(x);
    x += K * nu;
    Eigen::VectorXd& xs = smooth_[ch];
    xs += smooth * (x - xs);
    (*out)[ch] = in[ch] - hl.dot(xs.head(d));
    // What else the channel carries (the innovations' mean square; expected: that times
    // h^T P h + rho) against its line power per amplitude element, for rho.
    innovation_ms_[ch] += noise_gain * (nu * nu - innovation_ms_[ch]);
    noise += innovation_ms_[ch] / s;
    power += d > 0 ? x.head(d).squaredNorm() / d : 0.0;
    // Each amplitude element's prior, from the lines learnt: a line of amplitude A has elements of
    // variance A^2 / 2. A wing pair's lines take A^2 = |c_1|^2 + |c_2|^2: in step only their sum S
    // is learnt, split evenly, and two independent lines of power A^2 give E|S|^2 = 2 A^2.
    // The lines' error variance is then (S h)^T P (S h).
    for (int j = 0; j < d / 2; ++j) {
      const double own = x.segment<2>(2 * j).squaredNorm();
      const bool pair = set.lines[static_cast<std::size_t>(j)] < n_flap;
      const double a2 = pair ? own + x.segment<2>(2 * (j ^ 1)).squaredNorm() : own;
      sh.segment<2>(2 * j) = std::sqrt(0.5 * a2) * hl.segment<2>(2 * j);
    }
    const double q = sh.dot(set.P.topLeftCorner(d, d) * sh);
    // What the lines' error may hold beyond its usual part (which the EKF's configured input
    // noise holds: measured, bench_vibration --residual): q above its lower envelope per unit rho,
    // which comes down at once and goes up over kUsualTimeS (a part of the lines unknown for
    // longer than that is usual).
    residual_var_[ch] = std::max(0.0, q - set.rho * usual_[ch]);
    const double v = q / set.rho;
    usual_[ch] = v < usual_[ch] ? v : usual_[ch] + usual_gain * (v - usual_[ch]);
  }
  // rho, measured: what else the channels carry against their line power, within its bounds.
  if (power > 0.0) set.rho = std::clamp(noise / power, kRhoMin, kRhoMax);
  set.P.noalias() -= K * Ph.transpose();
  set.P = 0.5 * (set.P + set.P.transpose());
}

}  // namespace nimble
