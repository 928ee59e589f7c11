#include "sensors/mocap_emulator.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/attitude.h"
#include "sensors/sensor_config.h"

namespace nimble {
namespace {

[[noreturn]] void mocap_invalid(const std::string& field, double value, const std::string& allowed) {
  std::ostringstream out;
  out << "MocapConfig." << field << " = " << value << ": must be " << allowed;
  throw std::invalid_argument(out.str());
}

}  // namespace

std::int64_t MocapConfig::frame_period_us() const {
  return static_cast<std::int64_t>(std::llround(1e6 / frame_rate_hz));
}

double MocapConfig::position_sigma_m() const { return mean_position_error_m / (2.0 * std::sqrt(2.0 / M_PI)); }

double MocapConfig::expected_dropout_fraction() const {
  const double period_s = 1e-6 * static_cast<double>(frame_period_us());
  const double p = 1.0 - std::exp(-dropout_burst_rate_hz * period_s);
  const double m = std::max(1.0, dropout_mean_duration_s / period_s);
  return p * m / (1.0 + p * m);
}

void validate(const MocapConfig& c) {
  // Each parameter's range: the loader's table (sensors/sensor_config.h).
  try {
    check_params(mocap_params(), c);
  } catch (const std::invalid_argument& e) {
    throw std::invalid_argument(std::string("MocapConfig.") + e.what());
  }
  // And what relates two of them.
  const double period = 1e6 / c.frame_rate_hz;
  if (std::fabs(period - std::round(period)) > 1e-6) {
    mocap_invalid("frame_rate_hz", c.frame_rate_hz, "such that 1e6 / frame_rate_hz is a whole number of microseconds");
  }
  if (c.exposure_us > c.frame_period_us()) {
    mocap_invalid("exposure_us", static_cast<double>(c.exposure_us), "in [0, frame period]");
  }
}

MocapEmulator::MocapEmulator(const MocapConfig& config, std::uint64_t seed)
    : config_(config), noise_rng_(seed), dropout_rng_(seed ^ 0x9E3779B97F4A7C15ULL) {
  validate(config_);
  period_us_ = config_.frame_period_us();
  position_sigma_m_ = config_.position_sigma_m();
  const double period_s = 1e-6 * static_cast<double>(period_us_);
  burst_start_probability_ = 1.0 - std::exp(-config_.dropout_burst_rate_hz * period_s);
  burst_continue_probability_ = 1.0 - 1.0 / std::max(1.0, config_.dropout_mean_duration_s / period_s);
}

std::int64_t MocapEmulator::next_frame_utime() const {
  return config_.first_frame_start_utime + next_frame_ * period_us_ + config_.exposure_us / 2;
}

void MocapEmulator::start_at(std::int64_t utime) {
  if (frames_ > 0) return;
  const std::int64_t first_mid = config_.first_frame_start_utime + config_.exposure_us / 2;
  if (utime <= first_mid) {
    next_frame_ = 0;
    return;
  }
  next_frame_ = (utime - first_mid + period_us_ - 1) / period_us_;
}

bool MocapEmulator::in_forced_dropout(std::int64_t utime) const {
  for (const auto& window : forced_dropouts_) {
    if (utime >= window.first && utime < window.second) return true;
  }
  return false;
}

void MocapEmulator::add_forced_dropout(std::int64_t begin_utime, std::int64_t end_utime) {
  if (end_utime > begin_utime) forced_dropouts_.emplace_back(begin_utime, end_utime);
}

MocapPose MocapEmulator::capture(const MocapTruthInput& truth) {
  MocapPose pose;
  pose.utime = next_frame_utime();
  pose.frame_number = next_frame_;
  pose.seq = seq_++;
  pose.rigid_body_id = config_.rigid_body_id;
  ++next_frame_;
  ++frames_;

  // Occlusion chain (own generator).
  const double u = uniform_(dropout_rng_);
  in_burst_ = in_burst_ ? (u < burst_continue_probability_) : (u < burst_start_probability_);
  const bool occluded = in_burst_ || in_forced_dropout(pose.utime);

  // Noise (own generator; drawn for every frame so the sequence does not depend on dropouts).
  Eigen::Vector3d position_error, rotation_error;
  for (int i = 0; i < 3; ++i) position_error[i] = position_sigma_m_ * normal_(noise_rng_);
  for (int i = 0; i < 3; ++i) rotation_error[i] = config_.attitude_noise_sigma_rad[i] * normal_(noise_rng_);
  double latency = static_cast<double>(config_.latency_us);
  if (config_.latency_jitter_sigma_us > 0.0) {
    latency = std::max(0.0, latency + config_.latency_jitter_sigma_us * normal_(noise_rng_));
  }

  if (occluded) {
    ++dropped_;
    pose.tracking_valid = false;
    pose.num_markers = 0;
  } else {
    pose.tracking_valid = true;
    pose.position_ned_m = truth.position_ned_m + position_error;
    Eigen::Quaterniond q = (truth.q_body_to_ned.normalized() * quaternion_exp(rotation_error)).normalized();
    if (q.w() < 0.0) q.coeffs() = -q.coeffs();
    pose.q_body_to_ned = q;
    pose.mean_marker_error_m = position_error.norm();
    pose.num_markers = static_cast<std::int16_t>(config_.num_markers);
  }
  std::int64_t publish = pose.utime + static_cast<std::int64_t>(std::llround(latency));
  publish = std::max(publish, last_publish_utime_);  // never out of order
  last_publish_utime_ = publish;
  pose.publish_utime = publish;
  pose.latency_us = static_cast<std::int32_t>(publish - pose.utime);
  return pose;
}

std::vector<MocapPose> MocapEmulator::step(const MocapTruthInput& truth_now) {
  if (!have_previous_truth_) {
    start_at(truth_now.utime);
    previous_truth_ = truth_now;
    have_previous_truth_ = true;
  }
  if (truth_now.utime < previous_truth_.utime) {
    previous_truth_ = truth_now;  // time went backwards: restart interpolation, capture nothing
  }
  // A truth more than kMaxCatchUpFrames frames ahead of the schedule (a stray time, not a
  // sample of the run: found by fuzz_node_mocap) is not caught up frame by frame: the schedule
  // skips to it, and the frames skipped count as dropped.
  constexpr std::int64_t kMaxCatchUpFrames = 1000;
  if (truth_now.utime > next_frame_utime() &&
      (static_cast<double>(truth_now.utime) - static_cast<double>(next_frame_utime())) /
              static_cast<double>(period_us_) >
          static_cast<double>(kMaxCatchUpFrames)) {
    const std::int64_t skip = (truth_now.utime - next_frame_utime()) / period_us_;
    next_frame_ += skip;
    dropped_ += skip;
    previous_truth_ = truth_now;
  }
  while (next_frame_utime() <= truth_now.utime) {
    const std::int64_t t = next_frame_utime();
    MocapTruthInput at;
    at.utime = t;
    const std::int64_t span = truth_now.utime - previous_truth_.utime;
    if (span <= 0 || t <= previous_truth_.utime) {
      at.position_ned_m = span <= 0 ? truth_now.position_ned_m : previous_truth_.position_ned_m;
      at.q_body_to_ned = span <= 0 ? truth_now.q_body_to_ned : previous_truth_.q_body_to_ned;
    } else {
      const double s = static_cast<double>(t - previous_truth_.utime) / static_cast<double>(span);
      at.position_ned_m = (1.0 - s) * previous_truth_.position_ned_m + s * truth_now.position_ned_m;
      at.q_body_to_ned = previous_truth_.q_body_to_ned.slerp(s, truth_now.q_body_to_ned);
    }
    queue_.push_back(capture(at));
  }
  previous_truth_ = truth_now;
  std::vector<MocapPose> released;
  while (!queue_.empty() && queue_.front().publish_utime <= truth_now.utime) {
    released.push_back(queue_.front());
    queue_.pop_front();
  }
  return released;
}

}  // namespace nimble
