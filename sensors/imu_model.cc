#include "sensors/imu_model.h"

#include "sensors/sensor_config.h"

#include <cmath>
#include <sstream>
#include <stdexcept>

namespace nimble {
namespace {

[[noreturn]] void imu_invalid(const std::string& field, double value, const std::string& allowed) {
  std::ostringstream out;
  out << "ImuModelConfig." << field << " = " << value << ": must be " << allowed;
  throw std::invalid_argument(out.str());
}

void require_non_negative(const std::string& field, const Eigen::Vector3d& v) {
  for (int i = 0; i < 3; ++i) {
    if (!std::isfinite(v[i]) || v[i] < 0.0) imu_invalid(field + "[" + std::to_string(i) + "]", v[i], ">= 0");
  }
}

double clamp_axis(double value, double range, bool* clamped) {
  if (value > range) {
    *clamped = true;
    return range;
  }
  if (value < -range) {
    *clamped = true;
    return -range;
  }
  if (std::isnan(value)) {
    *clamped = true;
    return 0.0;
  }
  return value;
}

}  // namespace

std::vector<VibrationHarmonic> default_flapping_harmonics() {
  VibrationHarmonic first;
  first.harmonic = 1;
  first.gyro_amplitude_radps = Eigen::Vector3d(0.2, 0.2, 0.1);
  first.accel_amplitude_mps2 = Eigen::Vector3d(0.5, 0.3, 1.0);
  VibrationHarmonic second;
  second.harmonic = 2;
  second.gyro_amplitude_radps = Eigen::Vector3d(0.1, 0.1, 0.05);
  second.accel_amplitude_mps2 = Eigen::Vector3d(1.0, 0.2, 0.5);
  return {first, second};
}

std::int64_t ImuClock::stamp(std::int64_t rig_utime) const {
  if (identity()) return rig_utime;
  const double error_us = offset_s * 1e6 + drift_ppm * 1e-6 * static_cast<double>(rig_utime);
  return rig_utime + static_cast<std::int64_t>(std::floor(error_us + kStampRoundingPhase));
}

std::int64_t ImuClock::rig_utime(std::int64_t stamp_utime) const {
  if (identity()) return stamp_utime;
  // stamp() has the slope 1 + drift: the nearest guess (within a microsecond of the answer), then
  // the earliest neighbour that maps back exactly.
  const double guess = (static_cast<double>(stamp_utime) - offset_s * 1e6) / (1.0 + drift_ppm * 1e-6);
  if (!(std::fabs(guess) < 9e18)) return stamp_utime;  // no rig time: garbage, let the caller refuse it
  const std::int64_t t = std::llround(guess);
  for (const std::int64_t candidate : {t - 1, t, t + 1}) {
    if (stamp(candidate) == stamp_utime) return candidate;
  }
  return t;
}

namespace {

Eigen::Matrix3d error_matrix(const Eigen::Vector3d& scale, double xy, double xz, double yx, double yz, double zx,
                             double zy) {
  Eigen::Matrix3d m;
  m << 1.0 + scale.x(), xy, xz,  //
      yx, 1.0 + scale.y(), yz,   //
      zx, zy, 1.0 + scale.z();
  return m;
}

}  // namespace

Eigen::Matrix3d ImuModelConfig::gyro_error_matrix() const {
  return error_matrix(gyro_scale_factor, gyro_misalignment_xy_rad, gyro_misalignment_xz_rad, gyro_misalignment_yx_rad,
                      gyro_misalignment_yz_rad, gyro_misalignment_zx_rad, gyro_misalignment_zy_rad);
}

Eigen::Matrix3d ImuModelConfig::accel_error_matrix() const {
  return error_matrix(accel_scale_factor, accel_misalignment_xy_rad, accel_misalignment_xz_rad,
                      accel_misalignment_yx_rad, accel_misalignment_yz_rad, accel_misalignment_zx_rad,
                      accel_misalignment_zy_rad);
}

void validate(const ImuModelConfig& c) {
  // The scalar and vector parameters: the ranges of the loader's table (sensors/sensor_config.h).
  try {
    check_params(imu_params(), c);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("ImuModelConfig.") + e.what());
  }
  for (std::size_t i = 0; i < c.flapping_harmonics.size(); ++i) {
    const auto& h = c.flapping_harmonics[i];
    const std::string name = "flapping_harmonics[" + std::to_string(i) + "]";
    if (h.harmonic < 1) imu_invalid(name + ".harmonic", h.harmonic, ">= 1");
    require_non_negative(name + ".gyro_amplitude_radps", h.gyro_amplitude_radps);
    require_non_negative(name + ".accel_amplitude_mps2", h.accel_amplitude_mps2);
  }
}

ImuModel::ImuModel(const ImuModelConfig& config, std::uint64_t seed) : config_(config), rng_(seed) {
  validate(config_);
  clock_ = config_.clock();
  gyro_matrix_ = config_.gyro_error_matrix();
  accel_matrix_ = config_.accel_error_matrix();
  gyro_errors_ = gyro_matrix_ != Eigen::Matrix3d::Identity();
  accel_errors_ = accel_matrix_ != Eigen::Matrix3d::Identity();
  // Fixed draw order: turn-on biases, then vibration phases.
  for (int i = 0; i < 3; ++i) {
    gyro_bias_radps_[i] = config_.gyro_bias_initial_radps[i] + config_.gyro_bias_turn_on_sigma_radps * normal_(rng_);
  }
  for (int i = 0; i < 3; ++i) {
    accel_bias_mps2_[i] = config_.accel_bias_initial_mps2[i] + config_.accel_bias_turn_on_sigma_mps2 * normal_(rng_);
  }
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  for (std::size_t h = 0; h < config_.flapping_harmonics.size(); ++h) {
    Eigen::Vector3d g, a;
    for (int i = 0; i < 3; ++i) g[i] = phase(rng_);
    for (int i = 0; i < 3; ++i) a[i] = phase(rng_);
    harmonic_gyro_phase_rad_.push_back(g);
    harmonic_accel_phase_rad_.push_back(a);
  }
  for (int i = 0; i < 3; ++i) structural_gyro_phase_rad_[i] = phase(rng_);
  for (int i = 0; i < 3; ++i) structural_accel_phase_rad_[i] = phase(rng_);
  flap_phase_left_rad_ = phase(rng_);
  flap_phase_right_rad_ = phase(rng_);
}

ImuSample ImuModel::sample(const ImuTruthInput& truth) {
  double dt_s = 0.0;
  if (seq_ > 0) {
    if (truth.utime > last_utime_) {
      dt_s = 1e-6 * static_cast<double>(truth.utime - last_utime_);
    } else {
      ++non_increasing_time_;
    }
  }
  last_utime_ = truth.utime;

  // Bias random walk over the interval since the previous sample.
  if (dt_s > 0.0) {
    const double sq = std::sqrt(dt_s);
    for (int i = 0; i < 3; ++i) gyro_bias_radps_[i] += config_.gyro_bias_rw_radps_per_sqrts[i] * sq * normal_(rng_);
    for (int i = 0; i < 3; ++i) accel_bias_mps2_[i] += config_.accel_bias_rw_mps2_per_sqrts[i] * sq * normal_(rng_);
  }

  // Vibration phases advance with the current flapping frequencies.
  flap_phase_left_rad_ = std::fmod(flap_phase_left_rad_ + truth.flap_freq_left_radps * dt_s, 2.0 * M_PI);
  flap_phase_right_rad_ = std::fmod(flap_phase_right_rad_ + truth.flap_freq_right_radps * dt_s, 2.0 * M_PI);
  structural_phase_rad_ = std::fmod(structural_phase_rad_ + 2.0 * M_PI * config_.structural_mode_hz * dt_s, 2.0 * M_PI);

  Eigen::Vector3d vib_gyro = Eigen::Vector3d::Zero(), vib_accel = Eigen::Vector3d::Zero();
  if (config_.vibration_enabled) {
    for (std::size_t h = 0; h < config_.flapping_harmonics.size(); ++h) {
      const VibrationHarmonic& harm = config_.flapping_harmonics[h];
      const double k = harm.harmonic;
      for (int i = 0; i < 3; ++i) {
        vib_gyro[i] += 0.5 * harm.gyro_amplitude_radps[i] *
                       (std::sin(k * flap_phase_left_rad_ + harmonic_gyro_phase_rad_[h][i]) +
                        std::sin(k * flap_phase_right_rad_ + harmonic_gyro_phase_rad_[h][i]));
        vib_accel[i] += 0.5 * harm.accel_amplitude_mps2[i] *
                        (std::sin(k * flap_phase_left_rad_ + harmonic_accel_phase_rad_[h][i]) +
                         std::sin(k * flap_phase_right_rad_ + harmonic_accel_phase_rad_[h][i]));
      }
    }
    for (int i = 0; i < 3; ++i) {
      vib_gyro[i] +=
          config_.structural_gyro_amplitude_radps[i] * std::sin(structural_phase_rad_ + structural_gyro_phase_rad_[i]);
      vib_accel[i] +=
          config_.structural_accel_amplitude_mps2[i] * std::sin(structural_phase_rad_ + structural_accel_phase_rad_[i]);
    }
  }
  last_gyro_vibration_radps_ = vib_gyro;
  last_accel_vibration_mps2_ = vib_accel;

  // Scale factor and misalignment act on the true motion (untouched when there are none).
  const Eigen::Vector3d omega =
      gyro_errors_ ? Eigen::Vector3d(gyro_matrix_ * truth.omega_body_radps) : truth.omega_body_radps;
  const Eigen::Vector3d force =
      accel_errors_ ? Eigen::Vector3d(accel_matrix_ * truth.specific_force_body_mps2) : truth.specific_force_body_mps2;

  ImuSample out;
  out.utime = clock_.stamp(truth.utime);
  out.seq = seq_++;
  out.temperature_degc = config_.temperature_degc;
  std::uint8_t flags = 0;
  for (int i = 0; i < 3; ++i) {
    const double raw = omega[i] + gyro_bias_radps_[i] + vib_gyro[i] + config_.gyro_noise_sigma_radps[i] * normal_(rng_);
    bool clamped = false;
    out.gyro_radps[i] = clamp_axis(raw, config_.gyro_range_radps, &clamped);
    if (clamped) flags |= static_cast<std::uint8_t>(kSatGyroX << i);
  }
  for (int i = 0; i < 3; ++i) {
    const double raw =
        force[i] + accel_bias_mps2_[i] + vib_accel[i] + config_.accel_noise_sigma_mps2[i] * normal_(rng_);
    bool clamped = false;
    out.accel_mps2[i] = clamp_axis(raw, config_.accel_range_mps2, &clamped);
    if (clamped) flags |= static_cast<std::uint8_t>(kSatAccelX << i);
  }
  out.saturation_flags = flags;
  if (flags != 0) ++saturated_samples_;
  return out;
}

}  // namespace nimble
