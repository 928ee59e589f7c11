#include "ident/rig_log.h"

#include <algorithm>
#include <array>
#include <cstdint>
#include <fstream>
#include <functional>
#include <stdexcept>
#include <tuple>
#include <utility>

#include "contract/channels.h"
#include "contract/decode.h"
#include "contract/message_bounds.h"
#include "contract/messages.h"
#include "core/input_file.h"
#include "estimator/smoother.h"
#include "ident/data_check.h"
#include "lcmlog/lcm_log.h"

namespace nimble::ident {
namespace {

using namespace contract::channels;

/// What append() does with a sample whose time is not after the last one.
enum class Repeat {
  kSkip,     ///< keep the first sample of that time
  kReplace,  ///< a repeated time replaces the last sample (newer information about the same instant)
};

/// Appends a sample; a time before the last one is skipped, a repeated time per `repeat`.
void append(Channel& c, double t_s, double value, Repeat repeat = Repeat::kSkip) {
  if (!c.t_s.empty() && t_s <= c.t_s.back()) {
    if (repeat == Repeat::kReplace && t_s == c.t_s.back()) c.values.back() = value;
    return;
  }
  c.t_s.push_back(t_s);
  c.values.push_back(value);
}

/// The nine state channels (rates, body velocity, attitude) of `d`, made on first use.
void state_channels(FlightData& d, std::array<Channel*, 9>& c) {
  if (c[0] != nullptr) return;
  static const char* const kStates[] = {"p", "q", "r", "u", "v", "w", "phi", "theta", "psi"};
  for (int i = 0; i < 9; ++i) c[i] = &d.channels[kStates[i]];  // a std::map's elements stay put
}

/// Appends one sample of the nine states (rates, body velocity, attitude) at time t.
void append_states(FlightData& d, std::array<Channel*, 9>& c, double t, const Eigen::Vector3d& omega,
                   const Eigen::Vector3d& velocity, const Eigen::Vector3d& euler, Repeat repeat = Repeat::kSkip) {
  state_channels(d, c);
  for (int i = 0; i < 3; ++i) {
    append(*c[i], t, omega[i], repeat);
    append(*c[3 + i], t, velocity[i], repeat);
    append(*c[6 + i], t, euler[i], repeat);
  }
}

template <typename T>
T decode_or_throw(const lcmlog::LogEventRecord& ev, const std::string& file) {
  T msg{};
  std::string why;
  if (!contract::decode_exact(ev.data.data(), static_cast<int>(ev.data.size()), msg, &why)) {
    throw DataError(file, -1, static_cast<int>(ev.event_number), ev.channel,
                    "event at byte " + std::to_string(ev.offset) + ": " + why);
  }
  return msg;
}

/// The event's message as its value (contract/messages.h); a message that does not decode
/// exactly is an error naming the event.
template <typename T>
auto read_value(const lcmlog::LogEventRecord& ev, const std::string& file) {
  return contract::from_message(decode_or_throw<T>(ev, file));
}

/// Where each channel of a log's flight data comes from: its channel's field (states: the field of
/// ESTIMATE or TRUTH, whichever they are taken from).
constexpr std::pair<const char*, const char*> kStateFields[] = {
    {"p", "omega_body_radps[0]"},  {"q", "omega_body_radps[1]"},  {"r", "omega_body_radps[2]"},
    {"u", "velocity_body_mps[0]"}, {"v", "velocity_body_mps[1]"}, {"w", "velocity_body_mps[2]"},
    {"phi", "euler_rad[0]"},       {"theta", "euler_rad[1]"},     {"psi", "euler_rad[2]"},
};
struct InputOrigin {
  const char* name;
  const std::string* channel;
  const char* field;
};
const InputOrigin kInputFields[] = {
    {"delta_f", &kActuatorFeedback, "delta_f_radps"},
    {"delta_t", &kActuatorFeedback, "throttle_pct"},
    {"delta_d", &kActuatorFeedback, "dihedral_rad"},
    {"delta_w", &kActuatorFeedback, "wing_root_rad"},
    {"delta_f_cmd", &kActuatorCommand, "delta_f_radps"},
    {"phi_sp", &kAttitudeSetpoint, "roll_sp_rad"},
    {"ax", &kImu, "accel_mps2[0]"},
    {"ay", &kImu, "accel_mps2[1]"},
    {"az", &kImu, "accel_mps2[2]"},
};

/// Names the origin of every channel of `d` whose states come from `state_channel` ("" : none).
void set_origin(FlightData& d, const std::string& state_channel) {
  for (const auto& [name, field] : kStateFields) {
    if (d.has(name) && !state_channel.empty()) d.origin[name] = {state_channel, field};
  }
  for (const InputOrigin& o : kInputFields) {
    if (d.has(o.name)) d.origin[o.name] = {*o.channel, o.field};
  }
}

/// Names the origin of the states of StateSource::kSensors: the IMU's gyro, MOCAP_POSE.
void sensor_origin(FlightData& d) {
  static const std::string kDifferentiated = "position_m (differentiated)";
  const std::tuple<const char*, const std::string*, std::string> fields[] = {
      {"p", &kImu, "gyro_radps[0]"},
      {"q", &kImu, "gyro_radps[1]"},
      {"r", &kImu, "gyro_radps[2]"},
      {"phi", &kMocapPose, "quaternion_wxyz"},
      {"theta", &kMocapPose, "quaternion_wxyz"},
      {"psi", &kMocapPose, "quaternion_wxyz"},
      {"u", &kMocapPose, kDifferentiated},
      {"v", &kMocapPose, kDifferentiated},
      {"w", &kMocapPose, kDifferentiated},
  };
  for (const auto& [name, channel, field] : fields) {
    if (d.has(name)) d.origin[name] = {*channel, field};
  }
}

/// Each state source with its name.
constexpr std::pair<StateSource, const char*> kStateSourceNames[] = {
    {StateSource::kAuto, "auto"},         {StateSource::kEstimate, "estimate"}, {StateSource::kTruth, "truth"},
    {StateSource::kSmoothed, "smoothed"}, {StateSource::kSensors, "sensors"},
};

}  // namespace

const char* state_source_name(StateSource source) {
  for (const auto& [s, name] : kStateSourceNames) {
    if (s == source) return name;
  }
  return "?";
}

StateSource state_source_from_name(const std::string& name) {
  for (const auto& [s, n] : kStateSourceNames) {
    if (name == n) return s;
  }
  throw std::invalid_argument("state source '" + name + "': auto, estimate, truth, smoothed or sensors");
}

double estimate_time_s(std::int64_t utime, std::int64_t imu_utime) {
  // A time of the IMU sample after the publication cannot be right: keep the publication time.
  const std::int64_t t = (imu_utime >= 0 && imu_utime <= utime) ? imu_utime : utime;
  return static_cast<double>(t) * 1e-6;
}

bool is_lcm_log(const std::string& file) {
  try {
    check_input_file(file, InputKind::kLcmLog);  // no byte is read of a FIFO, a device or a huge file
  } catch (const InputFileError& e) {
    throw DataError(file, -1, -1, "", e.problem());
  }
  std::ifstream in(file, std::ios::binary);
  unsigned char magic[4] = {0, 0, 0, 0};
  in.read(reinterpret_cast<char*>(magic), 4);
  return in.gcount() == 4 && magic[0] == 0xED && magic[1] == 0xA1 && magic[2] == 0xDA && magic[3] == 0x01;
}

RigLogAssembler::RigLogAssembler(std::string source) : source_(std::move(source)) {}

bool RigLogAssembler::add(const std::string& channel, const void* data, int size, int64_t event_number,
                          int64_t offset) {
  event_.channel = channel;
  event_.event_number = event_number;
  event_.offset = offset;
  const auto* bytes = static_cast<const uint8_t*>(data);
  event_.data.assign(bytes, bytes + size);
  return add(event_);
}

Channel& RigLogAssembler::input(InputSlot slot, const char* name) {
  Channel*& c = input_channels_[slot];
  if (c == nullptr) c = &inputs_.channels[name];  // a std::map's elements stay put
  return *c;
}

template <class M>
bool RigLogAssembler::within(const lcmlog::LogEventRecord& ev, const M& message, double t_s) const {
  return beyond_ == nullptr || contract::message_within_bounds(ev.channel, message, t_s, *beyond_, ev.event_number);
}

bool RigLogAssembler::add(const lcmlog::LogEventRecord& event) {
  const lcmlog::LogEventRecord* ev = &event;
  const std::string& file = source_;
  if (ev->channel == kTruth) {
    const auto message = decode_or_throw<truth_state_t>(*ev, file);
    const double t = static_cast<double>(message.utime) * 1e-6;
    if (!within(*ev, message, t)) return true;
    const Truth m = contract::from_message(message);
    append_states(truth_, truth_states_, t, m.omega_body_radps, m.velocity_body_mps, m.euler_rad);
  } else if (ev->channel == kEstimate) {
    // The estimate describes the instant of the newest IMU sample it has integrated
    // (imu_utime): its rate is that sample's gyro minus the bias, attitude and velocity are
    // propagated to it. utime is when it was published, which in lockstep is the next
    // estimator tick, 1-2 ms later (see estimate_time_s()).
    const auto message = decode_or_throw<estimator_state_t>(*ev, file);
    const double t = estimate_time_s(message.utime, message.imu_utime);
    if (!within(*ev, message, t)) return true;
    const Estimate m = contract::from_message(message);
    append_states(estimate_, estimate_states_, t, m.omega_body_radps, m.velocity_body_mps, m.euler_rad,
                  Repeat::kReplace);
  } else if (ev->channel == kActuatorFeedback) {
    const auto message = decode_or_throw<actuator_feedback_t>(*ev, file);
    const double t = static_cast<double>(message.utime) * 1e-6;
    if (!within(*ev, message, t)) return true;
    const ActuatorFeedback m = contract::from_message(message);
    if (smoothing_) flaps_.push_back({m.utime, m.flap_freq_left_radps, m.flap_freq_right_radps});
    append(input(kDeltaF, "delta_f"), t, m.delta_f_radps);
    append(input(kDeltaT, "delta_t"), t, m.throttle_pct);
    append(input(kDeltaD, "delta_d"), t, m.dihedral_rad);
    append(input(kDeltaW, "delta_w"), t, m.wing_root_rad);
  } else if (ev->channel == kActuatorCommand) {
    // The flight board's command, the flap actuator's input (what the plant receives, over
    // LCM or after the CAN bridge, is this command, late by the link and any actuator delay).
    const auto message = decode_or_throw<actuator_command_t>(*ev, file);
    const double t = static_cast<double>(message.utime) * 1e-6;
    if (!within(*ev, message, t)) return true;
    const ActuatorCommand m = contract::from_message(message);
    const double df =
        m.mode == ActuatorCommand::kModeDeltaF ? m.delta_f_radps : m.flap_freq_left_radps - m.flap_freq_right_radps;
    append(input(kDeltaFCmd, "delta_f_cmd"), t, df);
  } else if (ev->channel == kControllerStatus) {
    if (!gain_set_.empty()) return false;
    gain_set_ = read_value<controller_status_t>(*ev, file).gain_set;
  } else if (ev->channel == kAttitudeSetpoint) {
    const auto message = decode_or_throw<attitude_setpoint_t>(*ev, file);
    const double t = static_cast<double>(message.utime) * 1e-6;
    if (!within(*ev, message, t)) return true;
    append(input(kPhiSp, "phi_sp"), t, contract::from_message(message).roll_sp_rad);
  } else if (ev->channel == kImu) {
    const auto message = decode_or_throw<imu_sample_t>(*ev, file);
    const double t = static_cast<double>(message.utime) * 1e-6;
    if (!within(*ev, message, t)) return true;
    const ImuSample m = contract::from_message(message);
    if (smoothing_) imu_.push_back(m);
    append(input(kAx, "ax"), t, m.accel_mps2[0]);
    append(input(kAy, "ay"), t, m.accel_mps2[1]);
    append(input(kAz, "az"), t, m.accel_mps2[2]);
  } else if (smoothing_ && ev->channel == kMocapPose) {
    poses_.push_back(read_value<mocap_pose_t>(*ev, file));
  } else {
    return false;
  }
  return true;
}

PrefilteredImu RigLogAssembler::imu_as_filtered(const SmoothingOptions& smoothing) const {
  if (!smoothing.prefilter.enabled) return {imu_, {}};
  return prefilter_imu(smoothing.prefilter, smoothing.imu_rate_hz, imu_, flaps_, smoothing.imu_rig_utime);
}

FlightData RigLogAssembler::smoothed_states(const SmoothingOptions& smoothing) const {
  const std::string& file = source_;
  if (!smoothing_) throw std::logic_error("RigLogAssembler: smoothed states need collect_for_smoothing()");
  if (imu_.empty()) throw DataError(file, -1, -1, kImu, "the log has no IMU samples to smooth");
  if (poses_.empty()) throw DataError(file, -1, -1, kMocapPose, "the log has no motion-capture frames to smooth");
  const PrefilteredImu imu = imu_as_filtered(smoothing);
  if (imu.imu.empty()) throw DataError(file, -1, -1, kImu, "the IMU filtering left no sample to smooth");
  std::vector<SmoothedSample> smoothed;
  if (smoothing.prefilter.enabled) {
    // The filter starts with the filtered samples (prefilter_imu leaves out those before its
    // lines are learnt): the frames from the first of them on.
    std::vector<MocapPose> poses;
    for (const MocapPose& pose : poses_) {
      if (pose.utime >= imu.imu.front().utime) poses.push_back(pose);
    }
    smoothed = smooth_flight(smoothing.ekf, smoothing.differentiator, imu.imu, poses, nullptr, &imu.input_var);
  } else {
    smoothed = smooth_flight(smoothing.ekf, smoothing.differentiator, imu_, poses_);
  }
  if (smoothed.empty()) {
    throw DataError(file, -1, -1, kMocapPose, "no motion-capture frame gave a measurement: nothing to smooth");
  }
  FlightData states;
  std::array<Channel*, 9> channels{};
  for (const SmoothedSample& s : smoothed) {
    append_states(states, channels, static_cast<double>(s.utime) * 1e-6, s.rate_radps, s.x.segment<3>(kU),
                  s.x.head<3>());
  }
  return states;
}

FlightData RigLogAssembler::sensor_states(const SmoothingOptions& smoothing) const {
  const std::string& file = source_;
  if (!smoothing_) throw std::logic_error("RigLogAssembler: sensor states need collect_for_smoothing()");
  if (imu_.empty()) throw DataError(file, -1, -1, kImu, "the log has no IMU samples (p, q, r)");
  if (poses_.empty()) throw DataError(file, -1, -1, kMocapPose, "the log has no motion-capture frames (phi, u)");
  FlightData states;
  // Rates: each IMU message's gyro at the stamp it carries, the IMU's own clock (through the
  // flight's on-board filtering when it had one).
  static const char* const kRates[] = {"p", "q", "r"};
  for (const ImuSample& m : imu_as_filtered(smoothing).imu) {
    for (int i = 0; i < 3; ++i)
      append(states.channels[kRates[i]], 1e-6 * static_cast<double>(m.utime), m.gyro_radps[i]);
  }
  // Attitude and velocity: the rig's differentiator on the frames in the order they were
  // published; a frame's attitude comes out once its velocity window is decided, so sort by time.
  MocapMeasurementBuilder builder(smoothing.differentiator);
  std::vector<PoseMeasurement> zs;
  for (const MocapPose& pose : poses_) {
    std::vector<PoseMeasurement> out = builder.push(pose);
    zs.insert(zs.end(), out.begin(), out.end());
  }
  const std::vector<PoseMeasurement> rest = builder.flush();
  zs.insert(zs.end(), rest.begin(), rest.end());
  if (zs.empty()) throw DataError(file, -1, -1, kMocapPose, "no motion-capture frame was tracked: no attitude");
  std::stable_sort(zs.begin(), zs.end(),
                   [](const PoseMeasurement& a, const PoseMeasurement& b) { return a.utime < b.utime; });
  static const char* const kEuler[] = {"phi", "theta", "psi"};
  static const char* const kVelocity[] = {"u", "v", "w"};
  for (const PoseMeasurement& z : zs) {
    const double t = 1e-6 * static_cast<double>(z.utime);
    for (int i = 0; i < 3; ++i) {
      append(states.channels[kEuler[i]], t, z.euler_rad[i]);
      if (z.has_velocity) append(states.channels[kVelocity[i]], t, z.velocity_body_mps[i]);
    }
  }
  if (!states.has("u")) {
    throw DataError(file, -1, -1, kMocapPose, "no motion-capture velocity window was complete: no u, v, w");
  }
  return states;
}

RigLogData RigLogAssembler::finish(StateSource source, const std::string& damage, const SmoothingOptions& smoothing) {
  const std::string& file = source_;
  FlightData& inputs = inputs_;
  if (!inputs.has("delta_f")) {
    throw DataError(file, -1, -1, kActuatorFeedback, "the log has no actuator feedback (delta_f, delta_t)");
  }
  // Servo inputs that never moved carry no information; leave them out so that the
  // identification does not try to estimate derivatives they cannot excite.
  for (const char* servo : {"delta_d", "delta_w"}) {
    bool moved = false;
    for (const double x : inputs.channels[servo].values) moved = moved || x != 0.0;
    if (!moved) inputs.channels.erase(servo);
  }
  // The states: the source asked for (auto: the estimator's if the log has them, else the truth).
  const StateSource chosen =
      source == StateSource::kAuto ? (estimate_.has("p") ? StateSource::kEstimate : StateSource::kTruth) : source;
  RigLogData out;
  if (chosen == StateSource::kSmoothed) {
    out.measured = smoothed_states(smoothing);
  } else if (chosen == StateSource::kSensors) {
    out.measured = sensor_states(smoothing);
  } else if (chosen == StateSource::kEstimate) {
    if (!estimate_.has("p")) throw DataError(file, -1, -1, kEstimate, "the log has no estimator output");
    out.measured = std::move(estimate_);
  } else {
    if (!truth_.has("p")) throw DataError(file, -1, -1, kTruth, "the log has neither ESTIMATE nor TRUTH");
    out.measured = truth_;
  }
  out.state_source = state_source_name(chosen);
  out.damage = damage;
  out.gain_set = gain_set_;
  out.measured.source = file;
  for (const auto& [name, c] : inputs.channels) out.measured.channels[name] = c;
  set_origin(out.measured, chosen == StateSource::kEstimate ? kEstimate : chosen == StateSource::kTruth ? kTruth : "");
  if (chosen == StateSource::kSensors) sensor_origin(out.measured);
  if (truth_.has("p")) {
    out.truth = std::move(truth_);
    out.truth.source = file + " (truth)";
    for (const auto& [name, c] : inputs.channels) out.truth.channels[name] = c;
    set_origin(out.truth, kTruth);
  }
  return out;
}

RigLogData read_rig_log(const std::string& file, StateSource source, const LogReadOptions& options) {
  lcmlog::LcmLogReader log(file, options.salvage);
  RigLogAssembler assembler(file);
  if (source == StateSource::kSmoothed || source == StateSource::kSensors) assembler.collect_for_smoothing();
  std::optional<BoundsTally> refuse;
  if (options.refuse_beyond_bounds && options.beyond_bounds == nullptr) refuse.emplace(*options.refuse_beyond_bounds);
  assembler.leave_out_beyond(refuse ? &*refuse : options.beyond_bounds);
  lcmlog::LogEventRecord record;
  while (log.next(&record)) {
    if (!assembler.add(record) && options.other_event) options.other_event(record);
  }
  if (refuse && !refuse->empty()) throw RefusedData(file, *refuse);
  return assembler.finish(source, log.damage(), options.smoothing);
}

FlightData read_flight_data(const std::string& file, const LogReadOptions& options, std::string* damage) {
  if (!is_lcm_log(file)) return read_flight_csv(file);
  RigLogData log = read_rig_log(file, options.states, options);
  if (damage) *damage = log.damage;
  return std::move(log.measured);
}

}  // namespace nimble::ident
