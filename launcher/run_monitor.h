#pragma once
/// RunMonitor: watches every message of a run (as the launcher logs it) and builds the
/// run summary: per-channel counts, rates, drops and lateness, loop timing reported by
/// the processes, faults, the flight itself (extremes, ranges, final state) and how the roll
/// followed the controller's reference.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <map>
#include <string>
#include <type_traits>
#include <utility>
#include <vector>

#include "core/rig_values.h"

namespace nimble::launcher {

/// What the monitor needs to know about the run to judge it.
struct MonitorConfig {
  bool lockstep = false;
  int64_t t0_monotonic_ns = 0;                   ///< real time: CLOCK_MONOTONIC of simulated time 0
  int64_t late_threshold_us = 2000;              ///< real time: a stream message later than this is late
  std::map<std::string, double> expected_hz;     ///< per channel; wall-clock channels per process
  std::vector<std::string> wall_clock_channels;  ///< rates of these are per wall second
  /// The run's processes: a HEARTBEAT, TIMING_HEALTH, FAULT, STEP_ACK or CAN_HEALTH naming
  /// another publisher (the launcher and its logger aside) is not trusted. Empty: any.
  std::vector<std::string> processes;
  /// Grid step of the flight's trace [us] (FlightSummary::trace_*); 0: no trace.
  int64_t trace_interval_us = 0;
};

struct ChannelSummary {
  int64_t count = 0;
  double rate_hz = 0.0;
  double expected_hz = 0.0;
  int64_t drops = 0;
  int64_t late = 0;
  int64_t malformed = 0;
  bool wall_clock = false;
};

struct TimingSummary {
  double loop_rate_hz = 0.0;
  int64_t loop_count = 0;
  int64_t overruns = 0;
  double jitter_p50_us = 0.0, jitter_p99_us = 0.0, jitter_max_us = 0.0;
  int64_t latency_count = 0;
  double latency_p50_us = 0.0, latency_p99_us = 0.0, latency_max_us = 0.0;
  /// What the process received, per channel: messages, and how many arrived late (real time:
  /// more than run.late_threshold_us after they were due, as the process itself saw them).
  struct Received {
    int64_t count = 0;
    int64_t late = 0;
  };
  std::map<std::string, Received> received;
  /// The control loop's stages the process timed (real time; ProcessNode::add_stage), in the
  /// order it named them.
  struct Stage {
    std::string name;
    int64_t count = 0;
    double p50_us = 0.0, p99_us = 0.0, max_us = 0.0;
  };
  std::vector<Stage> stages;
};

struct FaultRecord {
  std::string process;
  int severity = 0;
  int code = 0;
  std::string channel;
  std::string message;
  double rig_time_s = 0.0;
};

/// Flight statistics from TRUTH.
struct FlightSummary {
  int64_t samples = 0;
  double max_abs_p = 0.0, max_abs_v = 0.0, max_abs_phi = 0.0;
  double max_abs_theta = 0.0;  ///< pitch: stays at trim without a longitudinal model
  double max_abs_psi = 0.0;    ///< yaw: stays 0 without a four-state model
  double min_p = 0, max_p = 0, min_v = 0, max_v = 0, min_phi = 0, max_phi = 0;
  double min_df = 0, max_df = 0;
  double final_p = 0.0, final_v = 0.0, final_phi = 0.0;
  /// Vertical channel: height relative to the first TRUTH (up positive) [m], body w [m/s].
  double min_height_m = 0, max_height_m = 0, final_height_m = 0;
  double min_w = 0, max_w = 0, initial_w = 0;
  double last_sim_time_s = 0.0;
  /// Largest |height change| from the start [m].
  double max_abs_height_change_m() const { return std::max(std::fabs(min_height_m), std::fabs(max_height_m)); }
  bool finite = true;
  /// The trace (MonitorConfig::trace_interval_us > 0): p [rad/s], v [m/s] and phi [rad] of the
  /// first TRUTH at or after each grid time t_k = k trace_dt_s of rig time.
  double trace_dt_s = 0.0;
  std::vector<double> trace_p, trace_v, trace_phi;
};

/// Estimation error of ESTIMATE against TRUTH at the estimate's IMU time.
struct EstimatorSummary {
  int64_t samples = 0;
  double phi_rms_deg = 0.0, phi_max_deg = 0.0;
  double p_rms_radps = 0.0, v_rms_mps = 0.0;
  int64_t poses_accepted = 0, poses_rejected = 0, poses_missing = 0;
  int64_t poses_too_old = 0, poses_too_new = 0, velocity_windows_uncovered = 0;
  int64_t imu_rejected = 0, imu_gaps = 0;
};

/// One half-cycle of the roll tracking error: the error on one side of zero, from the zero
/// crossing before it left the dead band on that side to the one before it left it on the other.
struct TrackingHalfCycle {
  double start_s = 0.0;   ///< simulated time of the zero crossing that began it [s]
  double end_s = 0.0;     ///< of the one that ended it; the newest sample's for the last [s]
  double peak_deg = 0.0;  ///< the error's extreme in it, signed [deg]
  /// How far the roll reference moved in it (max - min, from the sample that left the dead
  /// band) [deg]: 0 when the loop moved on its own, the manoeuvre's size when it drove it.
  double reference_range_deg = 0.0;
};

/// Roll tracking: the true roll (TRUTH) against the controller's roll reference
/// (CONTROLLER_STATUS roll_ref_rad), error = reference - phi, once per control cycle with the
/// newest TRUTH at or before the cycle's utime. The controller's own roll_error_rad is against
/// the roll it measured, the estimate's when it flies on the estimator.
struct TrackingSummary {
  int64_t samples = 0;
  double rms_deg = 0.0;   ///< over the run [deg]
  double max_deg = 0.0;   ///< largest |error| [deg]
  double max_at_s = 0.0;  ///< when it was largest [s]
  /// The error's half-cycles in order, alternating in sign; the last is the one in progress.
  std::vector<TrackingHalfCycle> half_cycles;
};

/// Builds a TrackingSummary sample by sample. Zero crossings count only once the error has
/// left the dead band of +-kDeadBandDeg on the other side, so that jitter about zero does not
/// split a half-cycle.
class TrackingRecorder {
 public:
  /// Above the error's jitter in a calm hover (peak 0.94 deg, RMS 0.19-0.29 deg on hover.yaml,
  /// seeds 1-8), below the amplitudes the verdict judges (summary.oscillation_amplitude_deg).
  static constexpr double kDeadBandDeg = 1.0;
  /// One control cycle: the error and the roll reference it was against [deg].
  void add(double t_s, double error_deg, double reference_deg);
  /// The summary with the RMS of the samples so far.
  TrackingSummary summary() const;

 private:
  TrackingSummary s_;
  double sum2_ = 0.0;
  int side_ = 0;  ///< -1, +1: the side of the half-cycle in progress; 0 before the first
  double last_t_ = 0.0, last_e_ = 0.0;
  double crossing_s_ = 0.0;                           ///< the newest zero crossing [s]
  double reference_min_ = 0.0, reference_max_ = 0.0;  ///< in the half-cycle in progress [deg]
};

class RunMonitor {
 public:
  explicit RunMonitor(MonitorConfig config) : cfg_(std::move(config)) {}

  /// Feeds one raw message (channel, encoded bytes, receive time [ns, CLOCK_MONOTONIC]).
  /// `own_encoding`: the bytes are what the rig's own encoder wrote in this process (an
  /// in-process run's messages), which are decoded without checking that they encode back
  /// (contract::decode_as()); anything else is checked in full.
  void on_message(const std::string& channel, const void* data, int size, int64_t recv_ns, bool own_encoding = false);

  /// Heartbeat state of each process (heartbeat_t::STATE_*), -1 if never heard.
  int heartbeat_state(const std::string& process) const;
  /// The newest heartbeat of a process: state, pid, configuration digest and when it came.
  struct Heartbeat {
    int state = -1;
    int pid = 0;
    std::string digest;
    int64_t recv_ns = 0;  ///< CLOCK_MONOTONIC
    int64_t count = 0;    ///< heartbeats heard from it in the run
  };
  /// nullptr if the process was never heard.
  const Heartbeat* heartbeat(const std::string& process) const;
  /// Simulated time of the newest TRUTH [s].
  double sim_time_s() const { return flight_.last_sim_time_s; }
  int64_t truth_count() const { return flight_.samples; }
  const std::vector<FaultRecord>& faults() const { return faults_; }
  const FlightSummary& flight() const { return flight_; }
  /// Estimation errors (samples == 0 if the run had no estimator).
  EstimatorSummary estimator() const;
  /// Roll tracking (samples == 0 if the run had no controller).
  TrackingSummary tracking() const { return tracking_.summary(); }
  const std::map<std::string, TimingSummary>& timing() const { return timing_; }
  /// The newest CAN_HEALTH of each side of the CAN bridge (empty over the LCM link).
  const std::map<std::string, nimble::CanHealth>& can_health() const { return can_health_; }

  /// Channel table at the end of the run; `sim_duration_s` and `wall_duration_s` give the
  /// rate bases.
  std::map<std::string, ChannelSummary> channels(double sim_duration_s, double wall_duration_s) const;

  /// Sets the real-time origin once the run has started.
  void set_t0(int64_t t0_monotonic_ns) { cfg_.t0_monotonic_ns = t0_monotonic_ns; }

 private:
  struct Counter {
    int64_t count = 0;
    int64_t late = 0;
    int64_t malformed = 0;
    std::map<std::string, int64_t> last_seq;  // publisher -> seq
    int64_t drops = 0;
  };
  /// Counts gaps in `publisher`'s seq as drops; false (nothing counted) if `seq` does not
  /// continue its sequence (contract::seq_continues).
  bool accept_seq(Counter& c, const std::string& publisher, int64_t seq);
  /// A stream message's part of the figures: the flight from TRUTH (and the recent truth the
  /// others are held against), the estimator's error and counters, the roll tracking.
  void add_truth(const Truth& truth, int64_t utime);
  void add_estimate(const Estimate& estimate);
  void add_status(const ControllerStatus& status, int64_t utime);
  template <typename T>
  static const std::string& publisher_of(const T& msg, const std::string& fallback) {
    if constexpr (has_process<T>::value) {
      return msg.process;
    } else {
      return fallback;
    }
  }
  template <typename T, typename = void>
  struct has_process : std::false_type {};
  template <typename T>
  struct has_process<T, std::void_t<decltype(std::declval<T>().process)>> : std::true_type {};

  MonitorConfig cfg_;
  std::map<std::string, Counter> counters_;
  std::map<std::string, Heartbeat> heartbeat_;
  std::map<std::string, TimingSummary> timing_;
  std::map<std::string, nimble::CanHealth> can_health_;
  std::vector<FaultRecord> faults_;
  FlightSummary flight_;
  struct TruthPoint {
    double phi, p, v;
  };
  std::map<int64_t, TruthPoint> recent_truth_;  // utime -> truth, the last second
  double start_down_m_ = 0.0;                   ///< the first TRUTH's down position [m]
  double est_phi2_ = 0, est_p2_ = 0, est_v2_ = 0;
  EstimatorSummary est_;
  TrackingRecorder tracking_;
};

}  // namespace nimble::launcher
