#pragma once
/// Emulated motion-capture system (OptiTrack-like rigid-body tracking, thesis Section 8.1).
///
/// Frames are strictly periodic: frame n (n = 0, 1, ...) is exposed from
///   start_n = first_frame_start_utime + n * frame_period_us
/// for exposure_us, and its timestamp is the middle of the exposure,
///   utime_n = start_n + exposure_us / 2 (integer division).
/// Each frame is published latency_us (plus optional Gaussian jitter, never negative, never out of
/// order) after its timestamp.
///
/// Noise model:
///  - Position: isotropic Gaussian error per axis, independent per frame, with sigma such that the
///    mean 3-D error equals the published mean marker error (0.85 mm). For e ~ N(0, sigma^2 I3),
///    |e| is Maxwell distributed with E|e| = 2 sigma sqrt(2/pi) = 1.5958 sigma, hence
///      sigma = mean_error / (2 sqrt(2/pi)) = 0.85 mm / 1.5958 = 0.5327 mm.
///  - Attitude: q_measured = q_true * Exp(delta), delta ~ N(0, diag(sigma_x^2, sigma_y^2, sigma_z^2)),
///    a small rotation about the body axes, independent per frame.
///  - Dropouts (occlusion bursts): a two-state Markov chain per frame. While tracked, a burst starts
///    at a frame with probability p = 1 - exp(-burst_rate_hz * T) (T frame period); during a burst
///    each further frame stays occluded with probability 1 - 1/M, M = max(1, mean_duration / T),
///    so burst lengths are geometric with mean M frames. The long-run fraction of occluded frames is
///    p M / (1 + p M). Scripted dropouts can be added with add_forced_dropout().
/// An occluded frame is still published (frame numbers stay consecutive) with tracking_valid false,
/// position zero, identity quaternion and num_markers 0, as OptiTrack streams untracked bodies.
/// Noise and dropouts use separate seeded generators, so changing the dropout settings does not
/// change the noise of the tracked frames.

#include <cmath>
#include <cstdint>
#include <deque>
#include <random>
#include <utility>
#include <vector>

#include <Eigen/Core>
#include <Eigen/Geometry>

#include "contract/default_rates.h"
#include "core/rig_values.h"

namespace nimble {

/// Parameters of MocapEmulator.
struct MocapConfig {
  /// Frame rate [Hz]; thesis Section 8.1: 200 Hz. 1e6 / rate must be a whole number of microseconds.
  double frame_rate_hz = contract::kDefaultMocapFrameRateHz;
  /// Start of the exposure of frame 0 [us] (rig time).
  std::int64_t first_frame_start_utime = 0;
  /// Exposure time [us]. Assumption: 500 us (typical OptiTrack setting for fast bodies).
  std::int64_t exposure_us = 500;
  /// Latency from mid-exposure to publication [us]. Assumption: 5 ms (OptiTrack with streaming).
  std::int64_t latency_us = 5000;
  /// 1-sigma Gaussian jitter of the latency [us]; 0 for constant latency.
  double latency_jitter_sigma_us = 0.0;
  /// Mean 3-D position error [m]; paper Section II.B: 0.85 mm.
  double mean_position_error_m = 0.85e-3;
  /// Attitude noise, 1-sigma of the small rotation about body x y z [rad]. Default: the square roots
  /// of thesis Eq 8.2 R for phi, theta, psi (0.64, 0.43, 0.35 deg), read as the noise of the mocap
  /// Euler angles; consistent with 0.53 mm marker noise over a marker baseline of a few cm.
  Eigen::Vector3d attitude_noise_sigma_rad =
      Eigen::Vector3d(std::sqrt(0.125e-3), std::sqrt(0.057e-3), std::sqrt(0.037e-3));
  /// Occlusion bursts per second of tracked time [1/s]. Assumption: 0.2 (one burst per 5 s).
  double dropout_burst_rate_hz = 0.2;
  /// Mean duration of an occlusion burst [s]. Assumption: 0.05 s (10 frames).
  double dropout_mean_duration_s = 0.05;
  /// Rigid-body identifier reported in every frame [-].
  int rigid_body_id = 1;
  /// Markers of the rigid body [-]; thesis Fig 3: four markers (three on the crown, one below the autopilot).
  int num_markers = 4;

  /// Frame period [us] (rounded).
  std::int64_t frame_period_us() const;
  /// Per-axis position sigma [m] that gives mean_position_error_m as mean 3-D error (see header).
  double position_sigma_m() const;
  /// Long-run fraction of occluded frames of the random bursts [-] (scripted dropouts excluded).
  double expected_dropout_fraction() const;
};

/// Checks a MocapConfig.
/// @throws std::invalid_argument naming the field, its value and the allowed range.
void validate(const MocapConfig& config);

/// Truth at one instant, as needed by the emulator.
struct MocapTruthInput {
  /// Rig time [us].
  std::int64_t utime = 0;
  /// Position of the body origin in NED [m].
  Eigen::Vector3d position_ned_m = Eigen::Vector3d::Zero();
  /// Attitude, rotates body vectors into NED.
  Eigen::Quaterniond q_body_to_ned = Eigen::Quaterniond::Identity();
};

/// Transport-free motion-capture emulator. See the top of this header.
class MocapEmulator {
 public:
  /// @throws std::invalid_argument if `config` is invalid (see validate()).
  MocapEmulator(const MocapConfig& config, std::uint64_t seed);

  /// Timestamp (mid-exposure) of the next frame capture() will produce [us].
  std::int64_t next_frame_utime() const;
  /// Frame number of the next frame [-].
  std::int64_t next_frame_number() const { return next_frame_; }
  /// Moves the frame schedule so that the next frame is the first with timestamp >= `utime`.
  /// Only allowed before the first frame; afterwards frame numbers must stay consecutive.
  void start_at(std::int64_t utime);

  /// Produces the next frame from the truth at its timestamp (the frame is stamped with its
  /// scheduled time; truth.utime is not checked). Advances the schedule. Never throws.
  MocapPose capture(const MocapTruthInput& truth_at_mid_exposure);

  /// Convenience for a process fed with truth samples: captures every frame whose timestamp lies in
  /// (previous truth time, truth_now.utime], interpolating the truth linearly (position) and by
  /// slerp (attitude), queues it for its latency, and returns the frames whose publish_utime is
  /// <= truth_now.utime, in order. On the first call the schedule starts at truth_now.utime.
  std::vector<MocapPose> step(const MocapTruthInput& truth_now);

  /// Scripts an occlusion of every frame with timestamp in [begin_utime, end_utime).
  void add_forced_dropout(std::int64_t begin_utime, std::int64_t end_utime);

  /// Frames produced so far [-].
  std::int64_t frame_count() const { return frames_; }
  /// Frames produced with tracking_valid false [-].
  std::int64_t dropped_frame_count() const { return dropped_; }
  /// The configuration in use.
  const MocapConfig& config() const { return config_; }

 private:
  bool in_forced_dropout(std::int64_t utime) const;

  MocapConfig config_;
  std::int64_t period_us_;
  double position_sigma_m_;
  double burst_start_probability_;
  double burst_continue_probability_;
  std::mt19937_64 noise_rng_;
  std::mt19937_64 dropout_rng_;
  std::normal_distribution<double> normal_{0.0, 1.0};
  std::uniform_real_distribution<double> uniform_{0.0, 1.0};
  std::int64_t next_frame_ = 0;
  std::int64_t seq_ = 0;
  std::int64_t frames_ = 0;
  std::int64_t dropped_ = 0;
  bool in_burst_ = false;
  std::int64_t last_publish_utime_ = 0;
  std::vector<std::pair<std::int64_t, std::int64_t>> forced_dropouts_;
  bool have_previous_truth_ = false;
  MocapTruthInput previous_truth_;
  std::deque<MocapPose> queue_;
};

}  // namespace nimble
