#include "can_bridge/codec.h"

#include <cstring>

#include "can_bridge/crc8.h"
#include "can_bridge/signal_codec.h"

namespace nimble::can {

namespace {

using nimble::actuator_command_t;
using nimble::actuator_feedback_t;

/// An empty frame of the layout (zero payload, identifier and length set).
can_frame blank_frame(const FrameSpec& spec) {
  can_frame f;
  std::memset(&f, 0, sizeof f);
  f.can_id = spec.id;
  f.len = spec.length_bytes;
  return f;
}

/// Clamps, counts and packs one physical value.
void put(can_frame& f, const SignalSpec& s, double physical, EncodeStats& stats) {
  const ToRawResult r = to_raw(s, physical);
  if (r.saturated) ++stats.saturated_values;
  if (r.non_finite) ++stats.non_finite_values;
  pack_signal(f.data, f.len, s, r.raw);
}

/// Writes the rolling counter and the CRC (the last two steps of building any frame).
void seal(can_frame& f, uint8_t counter) {
  f.data[kCounterByte] = static_cast<uint8_t>((f.data[kCounterByte] & 0x0F) | ((counter & 0x0F) << 4));
  f.data[kCrcByte] = frame_crc(f.can_id & CAN_SFF_MASK, f.data, kCrcByte);
}

double physical(const can_frame& f, const SignalSpec& s) { return to_physical(s, unpack_signal(f.data, f.len, s)); }

int64_t raw(const can_frame& f, const SignalSpec& s) { return unpack_signal(f.data, f.len, s); }

/// Frame-level checks shared by both decoders: flags, identifier, length, checksum, ranges.
/// On kAccepted, *index is the frame's position in `frames`.
template <std::size_t N>
DecodeResult validate(const can_frame& f, const std::array<FrameSpec, N>& frames, std::size_t* index) {
  if (f.can_id & CAN_ERR_FLAG) return DecodeResult::kErrorFrame;
  if (f.can_id & (CAN_EFF_FLAG | CAN_RTR_FLAG)) return DecodeResult::kUnknownId;
  const uint32_t id = f.can_id & CAN_SFF_MASK;
  std::size_t i = 0;
  while (i < N && frames[i].id != id) ++i;
  if (i == N) return DecodeResult::kUnknownId;
  if (f.len != frames[i].length_bytes) return DecodeResult::kWrongLength;
  if (frame_crc(id, f.data, kCrcByte) != f.data[kCrcByte]) return DecodeResult::kBadChecksum;
  for (const SignalSpec& s : kAllSignals) {
    if (s.frame_id == id && !raw_in_range(s, raw(f, s))) return DecodeResult::kOutOfRange;
  }
  *index = i;
  return DecodeResult::kAccepted;
}

void count(DecodeResult r, DecodeStats& stats) {
  switch (r) {
    case DecodeResult::kAccepted: ++stats.frames_accepted; break;
    case DecodeResult::kMessageComplete:
      ++stats.frames_accepted;
      ++stats.messages;
      break;
    case DecodeResult::kUnknownId: ++stats.unknown_id; break;
    case DecodeResult::kWrongLength: ++stats.wrong_length; break;
    case DecodeResult::kBadChecksum: ++stats.bad_checksum; break;
    case DecodeResult::kStaleCounter: ++stats.stale_counter; break;
    case DecodeResult::kOutOfRange: ++stats.out_of_range; break;
    case DecodeResult::kErrorFrame: ++stats.error_frames; break;
  }
}

uint8_t counter_of(const can_frame& f) { return static_cast<uint8_t>(f.data[kCounterByte] >> 4); }

}  // namespace

// --- encoders ----------------------------------------------------------------------------------------
std::array<can_frame, kCommandFrames.size()> CommandEncoder::encode(const actuator_command_t& cmd) {
  double left = cmd.flap_freq_left_radps;
  double right = cmd.flap_freq_right_radps;
  int mode = actuator_command_t::MODE_LEFT_RIGHT;
  if (cmd.mode == actuator_command_t::MODE_DELTA_F) {
    left = cmd.flap_freq_collective_radps + 0.5 * cmd.delta_f_radps;
    right = cmd.flap_freq_collective_radps - 0.5 * cmd.delta_f_radps;
    mode = actuator_command_t::MODE_DELTA_F;
  } else if (cmd.mode != actuator_command_t::MODE_LEFT_RIGHT) {
    ++stats_.invalid_modes;
  }
  if (cmd.rolling_counter < 0 || cmd.rolling_counter >= static_cast<int>(kCounterModulo)) {
    ++stats_.invalid_counters;
  }
  const uint8_t counter = static_cast<uint8_t>(cmd.rolling_counter) & 0x0F;

  can_frame flap = blank_frame(kCmdFlap);
  put(flap, kCmdFlapFreqLeft, left, stats_);
  put(flap, kCmdFlapFreqRight, right, stats_);
  put(flap, kCmdThrottle, cmd.throttle_pct, stats_);
  pack_signal(flap.data, flap.len, kCmdMode, mode);
  seal(flap, counter);

  can_frame servo = blank_frame(kCmdServo);
  put(servo, kCmdDihedral, cmd.dihedral_rad, stats_);
  put(servo, kCmdWingRoot, cmd.wing_root_rad, stats_);
  pack_signal(servo.data, servo.len, kCmdSeq, static_cast<int64_t>(static_cast<uint64_t>(cmd.seq) & 0xFFFF));
  seal(servo, counter);

  ++stats_.messages;
  return {flap, servo};
}

std::array<can_frame, kFeedbackFrames.size()> FeedbackEncoder::encode(const actuator_feedback_t& fb) {
  const uint8_t counter = counter_;
  counter_ = static_cast<uint8_t>((counter_ + 1) % kCounterModulo);

  can_frame motor = blank_frame(kFbMotor);
  put(motor, kFbFlapFreqLeft, fb.flap_freq_left_radps, stats_);
  put(motor, kFbFlapFreqRight, fb.flap_freq_right_radps, stats_);
  put(motor, kFbThrottle, fb.throttle_pct, stats_);
  seal(motor, counter);

  can_frame servo = blank_frame(kFbServo);
  put(servo, kFbDihedral, fb.dihedral_rad, stats_);
  put(servo, kFbWingRoot, fb.wing_root_rad, stats_);
  seal(servo, counter);

  can_frame status = blank_frame(kFbStatus);
  if (fb.cmd_seq < 0) {
    pack_signal(status.data, status.len, kFbCmdSeq, 0);
    pack_signal(status.data, status.len, kFbCmdAge, kCmdAgeNoCommandRaw);
  } else {
    pack_signal(status.data, status.len, kFbCmdSeq, static_cast<int64_t>(static_cast<uint64_t>(fb.cmd_seq) & 0xFFFF));
    int64_t age_us = fb.cmd_age_us;
    if (age_us < 0 || age_us > kCmdAgeMax_us) {
      ++stats_.saturated_values;
      age_us = age_us < 0 ? 0 : kCmdAgeMax_us;
    }
    pack_signal(status.data, status.len, kFbCmdAge, age_us);
  }
  pack_signal(status.data, status.len, kFbSafeState, fb.safe_state ? 1 : 0);
  seal(status, counter);

  ++stats_.messages;
  return {motor, servo, status};
}

// --- assembly ----------------------------------------------------------------------------------------
FrameAssembler::FrameAssembler(std::size_t frame_count)
    : frame_count_(frame_count < 1 ? 1 : (frame_count > kMaxFrames ? kMaxFrames : frame_count)) {
  reset();
}

void FrameAssembler::reset() {
  last_counter_.fill(-1);
  pending_counter_.fill(-1);
}

bool FrameAssembler::accept_counter(std::size_t index, uint8_t counter, DecodeStats& stats) {
  if (index >= frame_count_) return false;
  const int last = last_counter_[index];
  if (last >= 0) {
    const unsigned advance = (counter + kCounterModulo - static_cast<unsigned>(last)) % kCounterModulo;
    if (advance == 0 || advance > kCounterMaxAdvance) return false;
    stats.counter_gaps += advance - 1;
  }
  last_counter_[index] = counter;
  return true;
}

bool FrameAssembler::store(std::size_t index, uint8_t counter, DecodeStats& stats) {
  if (index >= frame_count_) return false;
  if (pending_counter_[index] >= 0 && pending_counter_[index] != counter) ++stats.incomplete_messages;
  pending_counter_[index] = counter;
  for (std::size_t i = 0; i < frame_count_; ++i) {
    if (pending_counter_[i] != counter) return false;
  }
  pending_counter_.fill(-1);
  return true;
}

// --- decoders ----------------------------------------------------------------------------------------
DecodeResult CommandDecoder::decode(const can_frame& f, actuator_command_t* out) {
  std::size_t index = 0;
  DecodeResult r = validate(f, kCommandFrames, &index);
  if (r == DecodeResult::kAccepted && !assembler_.accept_counter(index, counter_of(f), stats_)) {
    r = DecodeResult::kStaleCounter;
  }
  if (r != DecodeResult::kAccepted) {
    count(r, stats_);
    return r;
  }
  if (kCommandFrames[index].id == kCmdFlap.id) {
    pending_.flap_freq_left_radps = physical(f, kCmdFlapFreqLeft);
    pending_.flap_freq_right_radps = physical(f, kCmdFlapFreqRight);
    pending_.throttle_pct = physical(f, kCmdThrottle);
    pending_.mode = static_cast<int8_t>(raw(f, kCmdMode));
  } else {
    pending_.dihedral_rad = physical(f, kCmdDihedral);
    pending_.wing_root_rad = physical(f, kCmdWingRoot);
    pending_.seq = raw(f, kCmdSeq);  // low 16 bits; unwrapped on completion
  }
  const uint8_t counter = counter_of(f);
  if (!assembler_.store(index, counter, stats_)) {
    count(DecodeResult::kAccepted, stats_);
    return DecodeResult::kAccepted;
  }
  if (out != nullptr) {
    *out = pending_;
    out->utime = 0;
    out->seq = unwrap_seq16(last_seq_, static_cast<uint16_t>(pending_.seq));
    out->delta_f_radps = out->flap_freq_left_radps - out->flap_freq_right_radps;
    out->flap_freq_collective_radps = 0.5 * (out->flap_freq_left_radps + out->flap_freq_right_radps);
    out->rolling_counter = static_cast<int8_t>(counter);
    out->source.clear();
    last_seq_ = out->seq;
  } else {
    last_seq_ = unwrap_seq16(last_seq_, static_cast<uint16_t>(pending_.seq));
  }
  count(DecodeResult::kMessageComplete, stats_);
  return DecodeResult::kMessageComplete;
}

void CommandDecoder::reset() {
  assembler_.reset();
  pending_ = actuator_command_t{};
  last_seq_ = -1;
}

DecodeResult FeedbackDecoder::decode(const can_frame& f, actuator_feedback_t* out) {
  std::size_t index = 0;
  DecodeResult r = validate(f, kFeedbackFrames, &index);
  if (r == DecodeResult::kAccepted && !assembler_.accept_counter(index, counter_of(f), stats_)) {
    r = DecodeResult::kStaleCounter;
  }
  if (r != DecodeResult::kAccepted) {
    count(r, stats_);
    return r;
  }
  const uint32_t id = kFeedbackFrames[index].id;
  if (id == kFbMotor.id) {
    pending_.flap_freq_left_radps = physical(f, kFbFlapFreqLeft);
    pending_.flap_freq_right_radps = physical(f, kFbFlapFreqRight);
    pending_.throttle_pct = physical(f, kFbThrottle);
  } else if (id == kFbServo.id) {
    pending_.dihedral_rad = physical(f, kFbDihedral);
    pending_.wing_root_rad = physical(f, kFbWingRoot);
  } else {
    const int64_t age_raw = raw(f, kFbCmdAge);
    if (age_raw == static_cast<int64_t>(kCmdAgeNoCommandRaw)) {
      pending_.cmd_seq = -1;
      pending_.cmd_age_us = -1;
    } else {
      pending_.cmd_seq = raw(f, kFbCmdSeq);  // low 16 bits; unwrapped on completion
      pending_.cmd_age_us = age_raw;
    }
    pending_.safe_state = raw(f, kFbSafeState) != 0;
  }
  if (!assembler_.store(index, counter_of(f), stats_)) {
    count(DecodeResult::kAccepted, stats_);
    return DecodeResult::kAccepted;
  }
  const int64_t cmd_seq =
      pending_.cmd_seq < 0 ? -1 : unwrap_seq16(last_cmd_seq_, static_cast<uint16_t>(pending_.cmd_seq));
  if (cmd_seq >= 0) last_cmd_seq_ = cmd_seq;
  if (out != nullptr) {
    *out = pending_;
    out->utime = 0;
    out->seq = 0;
    out->cmd_seq = cmd_seq;
    out->delta_f_radps = out->flap_freq_left_radps - out->flap_freq_right_radps;
  }
  count(DecodeResult::kMessageComplete, stats_);
  return DecodeResult::kMessageComplete;
}

void FeedbackDecoder::reset() {
  assembler_.reset();
  pending_ = actuator_feedback_t{};
  last_cmd_seq_ = -1;
}

// --- helpers -----------------------------------------------------------------------------------------
int64_t unwrap_seq16(int64_t previous, uint16_t low16) {
  if (previous < 0) return low16;
  int64_t candidate = (previous & ~int64_t{0xFFFF}) | low16;
  if (candidate - previous > 0x8000) {
    candidate -= 0x10000;
  } else if (previous - candidate >= 0x8000) {
    candidate += 0x10000;
  }
  return candidate < 0 ? low16 : candidate;
}

const char* to_string(DecodeResult result) {
  switch (result) {
    case DecodeResult::kAccepted: return "accepted";
    case DecodeResult::kMessageComplete: return "message_complete";
    case DecodeResult::kUnknownId: return "unknown_id";
    case DecodeResult::kWrongLength: return "wrong_length";
    case DecodeResult::kBadChecksum: return "bad_checksum";
    case DecodeResult::kStaleCounter: return "stale_counter";
    case DecodeResult::kOutOfRange: return "out_of_range";
    case DecodeResult::kErrorFrame: return "error_frame";
  }
  return "unknown";
}

}  // namespace nimble::can
