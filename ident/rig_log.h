#pragma once
/// Reading rig LCM logs as flight data for identification.
///
/// The measured data of a rig flight are what the lab would have: the states from the
/// estimator (ESTIMATE) when the log has it, else from the plant's truth (TRUTH); the
/// inputs from the actuator feedback (ACTUATOR_FB, 100 Hz: delta_f, delta_t, delta_d,
/// delta_w); the roll set-point from ATTITUDE_SP; specific force from IMU when present.
/// The truth is kept separately for checking.
///
/// Time stamps: every sample is placed at the instant it describes. For ESTIMATE that is
/// imu_utime, the newest IMU sample the estimate has integrated, not utime, the time it was
/// published: in lockstep the estimator publishes at its next 512 Hz tick, 0.97-1.95 ms
/// (mean 1.46 ms) after that sample, and stamping the states at utime delays p, v, phi
/// against delta_f (ACTUATOR_FB, stamped at the actuator state it reports) by that much,
/// which biases Lp by -15 % (ident/README.md, "Flying on the estimator").

#include <array>
#include <cstdint>
#include <functional>
#include <optional>
#include <string>

#include "contract/default_rates.h"
#include "core/data_bounds.h"
#include "core/rig_values.h"
#include "core/vehicle.h"
#include "estimator/ekf.h"
#include "estimator/imu_prefilter.h"
#include "estimator/mocap_measurement.h"
#include "estimator/smoother.h"
#include "ident/flight_data.h"
#include "lcmlog/lcm_log.h"

namespace nimble::ident {

/// Where the states of a rig log are taken from.
enum class StateSource {
  kAuto,      ///< ESTIMATE if the log has it, else TRUTH
  kEstimate,  ///< ESTIMATE (error if absent)
  kTruth,     ///< TRUTH
  kSmoothed,  ///< made offline from the log's IMU and MOCAP_POSE by the fixed-interval smoother
              ///< (estimator/smoother.h), as the thesis's identification data were made
  kSensors,   ///< the raw sensor channels as a lab records them, no fusion: p q r the IMU's gyro
              ///< at the stamps its messages carry (the IMU's own clock), phi theta psi from each
              ///< tracked MOCAP_POSE's quaternion at its stamp (mid-exposure), u v w the
              ///< motion-capture positions through the rig's velocity differentiator
              ///< (estimator/mocap_measurement.h; SmoothingOptions::differentiator) at the middle
              ///< of each window; ax ay az the IMU's accelerometer (as with every source)
};

/// The filter model of StateSource::kSmoothed (and the differentiator of kSensors): the flight's
/// own sensing configuration where it is known (the scenario's `sensing` section), else the
/// defaults, which are rig_configs/sensing/default_sensing.yaml's. smoothing_options()
/// (ident/flight_sensing.h) makes it from a sensing configuration.
struct SmoothingOptions {
  SmoothingOptions() = default;
  /// A flight without on-board IMU filtering.
  SmoothingOptions(const EkfConfig& ekf_config, const VelocityDifferentiatorConfig& differentiator_config)
      : ekf(ekf_config), differentiator(differentiator_config) {}

  EkfConfig ekf;
  VelocityDifferentiatorConfig differentiator;
  /// The on-board IMU filtering the flight's estimator ran (sensing.imu_prefilter). Enabled: the
  /// log's IMU passes the same filtering, fed with the log's ACTUATOR_FB (estimator/smoother.h,
  /// prefilter_imu), before the smoother (its residual variance the forward pass's input noise
  /// per sample) and before the rates of kSensors. Off (the default): the IMU as logged.
  ImuPrefilterConfig prefilter;
  double imu_rate_hz = contract::kDefaultImuRateHz;  ///< sensing.imu.sample_rate_hz, the prefilter's rate
  /// sensing.imu's clock: an IMU stamp [us] to the rig time of its sample (ImuClock::rig_utime);
  /// empty: the identity.
  std::function<std::int64_t(std::int64_t)> imu_rig_utime;
};

/// The name of a state source as commands and reports print it: "auto", "estimate", "truth",
/// "smoothed", "sensors".
const char* state_source_name(StateSource source);
/// The state source of such a name. @throws std::invalid_argument for another name.
StateSource state_source_from_name(const std::string& name);

/// A rig log as flight data.
struct RigLogData {
  FlightData measured;       ///< states (per StateSource), inputs, set-points, at their own rates
  FlightData truth;          ///< states from TRUTH with the same inputs (empty if no TRUTH)
  std::string state_source;  ///< "estimate", "truth", "smoothed" or "sensors"
  std::string gain_set;      ///< the roll gain set the controller flew (CONTROLLER_STATUS; empty if none)
  std::string damage;        ///< read with salvage from a damaged log: where and how much was left ("" if whole)
};

/// How to read a log.
struct LogReadOptions {
  /// A damaged log (truncated, corrupted) is an error naming the byte offset and the event;
  /// with salvage the events before the damage are read and RigLogData::damage says what was left.
  bool salvage = false;
  /// Called with every event the reader does not decode (channels it does not read, and
  /// CONTROLLER_STATUS after the first): e.g. to count those that are not a message of their
  /// channel's type (mcap::UndecodableCount), which the reader would otherwise pass over unseen.
  std::function<void(const lcmlog::LogEventRecord&)> other_event;
  /// Where read_flight_data() takes the states from (read_rig_log() takes its own argument).
  StateSource states = StateSource::kAuto;
  /// The smoother's model, for StateSource::kSmoothed.
  SmoothingOptions smoothing;
  /// When set: every message read is checked against the vehicle's physical bounds
  /// (contract/message_bounds.h); a message with a field beyond them is left out, each such field
  /// counted here by channel, field and time (what an export does; the analyses leave this unset
  /// and refuse the record instead, ident/data_check.h).
  BoundsTally* beyond_bounds = nullptr;
  /// When set (and beyond_bounds is not): every message read is checked against this vehicle's
  /// physical bounds, and a log with a message beyond them is refused (RefusedData, naming the
  /// channel, field, time and count, ident/data_check.h): what the analyses do.
  std::optional<Vehicle> refuse_beyond_bounds;
};

/// Time [s] an estimator_state_t describes: imu_utime [us], or utime [us] if imu_utime is
/// negative or after utime.
double estimate_time_s(std::int64_t utime, std::int64_t imu_utime);

/// True if `file` starts with the LCM log event sync word.
/// @throws DataError naming the file, before any byte is read, if it does not exist, is no regular
///         file (a FIFO, /dev/zero) or is above the bound of an LCM log (core/input_file.h).
bool is_lcm_log(const std::string& file);

/// What read_rig_log() does with a log, one message at a time: the rig's messages, in the order
/// they were published (the order a recorder writes them), become RigLogData. read_rig_log()
/// feeds it every event of the file; an in-process flight can feed it every message it
/// publishes, and the workflow then sees what it would see from the flight's log.
class RigLogAssembler {
 public:
  /// `source` names the data in errors and in FlightData::source.
  explicit RigLogAssembler(std::string source);
  RigLogAssembler(const RigLogAssembler&) = delete;  // it holds pointers into its own channels
  RigLogAssembler& operator=(const RigLogAssembler&) = delete;
  /// One message: its channel and encoded bytes. `event_number` and `offset` name it in errors
  /// (the log's event number and byte offset; -1 for a message that was never in a file).
  /// Returns false for a message it does not read (a channel it does not use, CONTROLLER_STATUS
  /// after the first), which it does not decode either.
  /// @throws DataError naming the event and channel of a message it reads that does not decode.
  bool add(const std::string& channel, const void* data, int size, std::int64_t event_number = -1,
           std::int64_t offset = -1);
  /// Keep the IMU samples and motion-capture frames (decoding MOCAP_POSE, which it otherwise
  /// passes over) for finish(StateSource::kSmoothed or kSensors). Call before the first add().
  void collect_for_smoothing() { smoothing_ = true; }
  /// Leave out every message with a field beyond the bounds of `tally`, counting them there
  /// (LogReadOptions::beyond_bounds). Call before the first add().
  void leave_out_beyond(BoundsTally* tally) { beyond_ = tally; }
  /// One event of a log. @throws DataError as above.
  bool add(const lcmlog::LogEventRecord& event);
  /// The data, states per `source`; `damage` goes to RigLogData::damage. Call once.
  /// @throws DataError for a missing channel, as read_rig_log().
  /// @throws DataError for kSmoothed or kSensors on a log without IMU or MOCAP_POSE, or
  ///         without collect_for_smoothing().
  RigLogData finish(StateSource source = StateSource::kAuto, const std::string& damage = "",
                    const SmoothingOptions& smoothing = {});

 private:
  /// The states smoothed offline from the collected IMU samples and frames (finish()).
  FlightData smoothed_states(const SmoothingOptions& smoothing) const;
  /// The raw sensor channels of the collected IMU samples and frames (finish(), kSensors).
  FlightData sensor_states(const SmoothingOptions& smoothing) const;
  /// The collected IMU samples through the flight's on-board filtering (as logged when off).
  PrefilteredImu imu_as_filtered(const SmoothingOptions& smoothing) const;
  enum InputSlot { kDeltaF, kDeltaT, kDeltaD, kDeltaW, kDeltaFCmd, kPhiSp, kAx, kAy, kAz, kInputSlots };
  /// The input channel `name`, made on first use; looked up by slot after that.
  Channel& input(InputSlot slot, const char* name);

  std::string source_;
  FlightData estimate_, truth_, inputs_;
  std::array<Channel*, 9> estimate_states_{}, truth_states_{};  ///< p q r u v w phi theta psi, once made
  std::array<Channel*, kInputSlots> input_channels_{};
  std::string gain_set_;
  /// The message, decoded, passes the bounds (true without leave_out_beyond()).
  template <class M>
  bool within(const lcmlog::LogEventRecord& event, const M& message, double t_s) const;

  bool smoothing_ = false;
  BoundsTally* beyond_ = nullptr;
  std::vector<ImuSample> imu_;          ///< for the smoother
  std::vector<MocapPose> poses_;        ///< for the smoother
  std::vector<FlapFrequencies> flaps_;  ///< ACTUATOR_FB's flapping frequencies, for the IMU filtering
  lcmlog::LogEventRecord event_;        ///< reused by add(channel, data, ...)
};

/// Reads a rig log (the LCM log format, through lcmlog::LcmLogReader: damage is never read past).
/// @throws DataError naming the log, the byte offset and event of damage, or the event number
///         (as the row) and channel of a message that does not decode, or a missing channel.
RigLogData read_rig_log(const std::string& file, StateSource source = StateSource::kAuto,
                        const LogReadOptions& options = {});

/// Reads flight data from a rig log (its measured data) or a CSV file, by content. `damage`
/// (if given) receives RigLogData::damage of a log read with salvage.
FlightData read_flight_data(const std::string& file, const LogReadOptions& options = {}, std::string* damage = nullptr);

}  // namespace nimble::ident
