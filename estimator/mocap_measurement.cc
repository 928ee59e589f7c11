#include "estimator/mocap_measurement.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>

#include "core/attitude.h"

namespace nimble {
namespace {

std::int64_t positive_mod(std::int64_t a, std::int64_t m) {
  const std::int64_t r = a % m;
  return r < 0 ? r + m : r;
}

}  // namespace

void validate(const VelocityDifferentiatorConfig& c) {
  std::ostringstream out;
  if (c.span_frames < 2 || c.span_frames % 2 != 0 || c.span_frames > 1000) {
    out << "VelocityDifferentiatorConfig.span_frames = " << c.span_frames << ": must be even and in [2, 1000]";
    throw std::invalid_argument(out.str());
  }
  if (c.stride_frames < 1 || c.stride_frames > 1000) {
    out << "VelocityDifferentiatorConfig.stride_frames = " << c.stride_frames << ": must be in [1, 1000]";
    throw std::invalid_argument(out.str());
  }
  if (c.span_frames % c.stride_frames == 0) {
    out << "VelocityDifferentiatorConfig.stride_frames = " << c.stride_frames << ": span_frames (" << c.span_frames
        << ") must not be a multiple of it, otherwise successive velocity pairs share a frame and "
           "the velocity noise is not white";
    throw std::invalid_argument(out.str());
  }
}

double differentiated_velocity_sigma_mps(double position_sigma_m, double span_s) {
  return std::sqrt(2.0) * position_sigma_m / span_s;
}

MocapMeasurementBuilder::MocapMeasurementBuilder(const VelocityDifferentiatorConfig& config) : config_(config) {
  validate(config_);
}

bool MocapMeasurementBuilder::is_middle(std::int64_t n) const {
  return positive_mod(n - config_.span_frames / 2, config_.stride_frames) == 0;
}

bool MocapMeasurementBuilder::is_end(std::int64_t n) const {
  return positive_mod(n - config_.span_frames, config_.stride_frames) == 0;
}

const MocapMeasurementBuilder::Frame* MocapMeasurementBuilder::find(std::int64_t frame_number) const {
  for (const Frame& f : recent_) {
    if (f.frame_number == frame_number) return &f;
  }
  return nullptr;
}

PoseMeasurement MocapMeasurementBuilder::attitude_only(const Frame& frame) {
  PoseMeasurement m;
  m.utime = frame.utime;
  m.frame_number = frame.frame_number;
  m.euler_rad = euler_zyx_from_quaternion(frame.q_body_to_ned);
  m.has_velocity = false;
  ++attitude_only_measurements_;
  return m;
}

std::vector<PoseMeasurement> MocapMeasurementBuilder::push(const MocapPose& pose) {
  std::vector<PoseMeasurement> out;
  const std::int64_t n = pose.frame_number;
  if (have_last_ && n <= last_frame_number_) {
    ++frames_out_of_order_;
    return out;
  }
  if (have_last_ && n > last_frame_number_ + 1) frames_missing_ += n - last_frame_number_ - 1;
  have_last_ = true;
  last_frame_number_ = n;
  ++frames_received_;
  if (!pose.tracking_valid) ++frames_invalid_;

  Frame frame;
  frame.frame_number = n;
  frame.utime = pose.utime;
  frame.valid = pose.tracking_valid;
  frame.position_ned_m = pose.position_ned_m;
  frame.q_body_to_ned = pose.q_body_to_ned;
  recent_.push_back(frame);
  while (!recent_.empty() && recent_.front().frame_number < n - config_.span_frames) recent_.pop_front();

  const std::int64_t half = config_.span_frames / 2;
  // Middle frames whose end frame can no longer arrive: attitude only.
  while (!held_.empty() && held_.front().frame_number + half < n) {
    out.push_back(attitude_only(held_.front()));
    held_.pop_front();
  }
  // The pair that ends at this frame.
  if (is_end(n) && !held_.empty() && held_.front().frame_number == n - half) {
    const Frame middle = held_.front();
    held_.pop_front();
    const Frame* start = find(n - config_.span_frames);
    if (frame.valid && start != nullptr && start->valid && frame.utime > start->utime) {
      const double span_s = 1e-6 * static_cast<double>(frame.utime - start->utime);
      const Eigen::Vector3d v_ned = (frame.position_ned_m - start->position_ned_m) / span_s;
      PoseMeasurement m;
      m.utime = middle.utime;
      m.frame_number = middle.frame_number;
      m.euler_rad = euler_zyx_from_quaternion(middle.q_body_to_ned);
      m.has_velocity = true;
      m.velocity_body_mps = middle.q_body_to_ned.normalized().toRotationMatrix().transpose() * v_ned;
      m.velocity_window_start_utime = start->utime;
      m.velocity_window_end_utime = frame.utime;
      ++velocity_measurements_;
      out.push_back(m);
    } else {
      out.push_back(attitude_only(middle));
    }
  }
  // This frame's own attitude.
  if (frame.valid) {
    if (is_middle(n)) {
      held_.push_back(frame);
    } else {
      out.push_back(attitude_only(frame));
    }
  }
  std::stable_sort(out.begin(), out.end(),
                   [](const PoseMeasurement& a, const PoseMeasurement& b) { return a.utime < b.utime; });
  return out;
}

std::vector<PoseMeasurement> MocapMeasurementBuilder::flush() {
  std::vector<PoseMeasurement> out;
  while (!held_.empty()) {
    out.push_back(attitude_only(held_.front()));
    held_.pop_front();
  }
  return out;
}

}  // namespace nimble
