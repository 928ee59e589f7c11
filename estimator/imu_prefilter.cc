#include "estimator/imu_prefilter.h"

#include <algorithm>
#include <cmath>
#include <climits>
#include <stdexcept>

namespace nimble {

const ParamTable<ImuPrefilterConfig>& imu_prefilter_params() {
  using C = ImuPrefilterConfig;
  static const ParamTable<C> table = {
      {"enabled", &C::enabled, Range::any(), "-", "the on-board IMU filtering before the EKF on or off"},
      {"flap_harmonics", &C::flap_harmonics, Range::closed(0, 8), "-",
       "notches at k x each wing pair's measured flapping frequency (ACTUATOR_FB), k = 1..this"},
      {"flap_notch_bandwidth_hz", &C::flap_notch_bandwidth_hz, Range::closed(0.1, 20.0), "Hz",
       "-3 dB width of each flapping notch; assumption: wide enough for the feedback's 10 ms age while delta_f moves"},
      {"initial_flap_freq_hz", &C::initial_flap_freq_hz, Range::closed(0.0, 40.0), "Hz",
       "flapping frequency before the first actuator feedback; thesis: 17 Hz"},
      {"structural_notch_hz", &C::structural_notch_hz, Range::closed(0.0, 100.0), "Hz",
       "fixed notch (0: none); thesis Section 8.3: the yaw-rate line at about 11 Hz"},
      {"structural_notch_bandwidth_hz", &C::structural_notch_bandwidth_hz, Range::closed(0.1, 20.0), "Hz",
       "-3 dB width of the fixed notch"},
      {"structural_notch_gyro", &C::structural_notch_gyro, Range::any(), "-", "the fixed notch on the gyro channels"},
      {"structural_notch_accel", &C::structural_notch_accel, Range::any(), "-",
       "the fixed notch on the accelerometer channels"},
      {"accel", &C::accel, Range::any(), "-", "the flapping notches on the accelerometer channels too"},
      {"lead_compensation", &C::lead_compensation, Range::any(), "-",
       "a one-tap lead that gives the chain zero group delay at DC (an attitude integrated from the rates does not lag)"},
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
  wb_flap_ = 2.0 * M_PI * config_.flap_notch_bandwidth_hz;
  wb_structural_ = 2.0 * M_PI * config_.structural_notch_bandwidth_hz;
  lines_.resize(2 * static_cast<std::size_t>(config_.flap_harmonics) + 1);
  for (auto& a : amp_) a.assign(lines_.size(), {0.0, 0.0});
  for (auto& d : demod_) d.assign(2 * lines_.size(), {0.0, 0.0});
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
  // On from the newest measurement along the last two, for at most two of their intervals.
  const double span = static_cast<double>(b.utime - a.utime);
  const double ahead = std::min(static_cast<double>(utime - b.utime), 2.0 * span);
  return std::max(0.0, fb + (fb - (left ? a.left : a.right)) * ahead / span);
}

ImuSample ImuPrefilter::filter(const ImuSample& raw, std::int64_t rig_utime) {
  if (!config_.enabled) return raw;
  const std::array<double, 6> in{raw.gyro_radps.x(), raw.gyro_radps.y(), raw.gyro_radps.z(),
                                 raw.accel_mps2.x(), raw.accel_mps2.y(), raw.accel_mps2.z()};
  if (!started_) {
    first_utime_ = last_utime_ = raw.utime;
    last_out_ = in;
    level_ = in;
    started_ = true;
  }
  const std::int64_t dt_us = raw.utime - last_utime_;
  const double dt_s = 1e-6 * static_cast<double>(std::max<std::int64_t>(dt_us, 0));
  last_utime_ = std::max(last_utime_, raw.utime);
  // The lines' frequencies at this sample and their references moved on over the interval.
  const double left = flap_radps(true, rig_utime), right = flap_radps(false, rig_utime);
  const std::size_t n_flap = lines_.size() - 1;
  for (std::size_t i = 0; i < lines_.size(); ++i) {
    const int k = static_cast<int>(i / 2) + 1;
    const double f_hz = i == n_flap ? config_.structural_notch_hz : k * (i % 2 == 0 ? left : right) / (2.0 * M_PI);
    Line& l = lines_[i];
    l.w = (f_hz > 0.0 && f_hz < 0.45 * fs_) ? 2.0 * M_PI * f_hz : 0.0;
    l.theta = std::fmod(l.theta + l.w * dt_s, 2.0 * M_PI);
    l.ref = {std::cos(l.theta), std::sin(l.theta)};
  }
  // The gain: a running mean at first (2 dt / elapsed), then the notch's own 2 dt / T = wB dt.
  const double elapsed_s = 1e-6 * static_cast<double>(last_utime_ - first_utime_) + dt_s;
  const auto gain = [&](double wb) { return elapsed_s > 0.0 ? 2.0 * dt_s * std::max(0.5 * wb, 1.0 / elapsed_s) : 0.0; };
  const double g_flap = gain(wb_flap_), g_structural = gain(wb_structural_);
  // Each channel's level m: its running mean over the start (kStartS), then held.
  if (elapsed_s <= kStartS && elapsed_s > 0.0) {
    for (int ch = 0; ch < 6; ++ch) level_[ch] += dt_s / elapsed_s * (in[ch] - level_[ch]);
  }
  const double residual_gain = -std::expm1(-dt_s / kResidualTimeS);
  ImuSample out = raw;
  for (int ch = 0; ch < 6; ++ch) {
    const bool gyro = ch < 3;
    const bool flap = gyro || config_.accel;
    const bool structural = gyro ? config_.structural_notch_gyro : config_.structural_notch_accel;
    std::vector<std::complex<double>>& c = amp_[ch];
    // Every line of the channel at once: e = y - sum of lines, each line learnt from e - m.
    double lines = 0.0, g_sum = 0.0, inv_w2 = 0.0, wb_inv_w2 = 0.0;
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      const Line& l = lines_[i];
      if (l.w == 0.0 || !(i == n_flap ? structural : flap)) continue;
      lines += (c[i] * l.ref).real();
      g_sum += i == n_flap ? g_structural : g_flap;
      inv_w2 = 1.0 / (l.w * l.w);
      wb_inv_w2 += (i == n_flap ? wb_structural_ : wb_flap_) * inv_w2;
    }
    // The recursion d[k+1] = (d[k] + g e[k]) e^{j w dt} of a rotating line d = c e^{j theta} holds
    // -g/2 of a constant part of e - m: with the sum G of the gains,
    // e = (y - lines + G m / 2) / (1 + G / 2) is exactly y for a constant y, whatever m (unit gain
    // at DC; without it 1 / (1 - G/2), 2.5 % per line at 4 Hz), and still zero at every line.
    const double m = level_[ch];
    const double e = (in[ch] - lines + 0.5 * g_sum * m) / (1.0 + 0.5 * g_sum);
    // What is left of each line, (e - m) e^{-j theta} through two first-order low-passes (its
    // mean is half the line's remaining complex amplitude): the residual's variance is the sum of
    // 2 |mean|^2 over the lines.
    double residual = 0.0;
    for (std::size_t i = 0; i < lines_.size(); ++i) {
      const Line& l = lines_[i];
      if (l.w == 0.0 || !(i == n_flap ? structural : flap)) continue;
      const std::complex<double> demod = (e - m) * std::conj(l.ref);
      c[i] += (i == n_flap ? g_structural : g_flap) * demod;
      std::complex<double>& d1 = demod_[ch][2 * i];
      std::complex<double>& d2 = demod_[ch][2 * i + 1];
      d1 += residual_gain * (demod - d1);
      d2 += residual_gain * (d1 - d2);
      residual += 2.0 * std::norm(d2);
    }
    residual_var_[ch] = residual;
    // The lead: the chain's delay at DC once the lines are learnt, sum of wB / w^2.
    const double lead = config_.lead_compensation && dt_s > 0.0 ? wb_inv_w2 / dt_s : 0.0;
    const double led = e + lead * (e - last_out_[ch]);
    last_out_[ch] = e;
    if (ch == 0) dc_delay_s_ = wb_inv_w2;
    (gyro ? out.gyro_radps : out.accel_mps2)[ch % 3] = led;
  }
  return out;
}

}  // namespace nimble
