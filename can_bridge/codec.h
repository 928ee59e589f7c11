#pragma once
/// Encoding of the rig's LCM actuator messages into CAN frames and back (layout: frame_layout.h).
///
/// Encoders never fail: out-of-range and non-finite values are clamped and counted. Decoders never
/// throw: every frame gets a DecodeResult, every result is counted, and a message is only produced
/// once all of its frames have arrived with the same rolling counter.

#include <linux/can.h>

#include <array>
#include <cstdint>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>

#include "can_bridge/frame_layout.h"

namespace nimble::can {

/// Counters of what the encoders had to change.
struct EncodeStats {
  uint64_t messages = 0;           ///< messages encoded
  uint64_t saturated_values = 0;   ///< values outside their documented range, clamped to it
  uint64_t non_finite_values = 0;  ///< NaN or infinite values, sent as 0 (clamped into range)
  uint64_t invalid_modes = 0;      ///< command modes other than MODE_*; sent as MODE_LEFT_RIGHT
  uint64_t invalid_counters = 0;   ///< rolling_counter outside 0..15; sent modulo 16
};

/// actuator_command_t -> kCmdFlap, kCmdServo.
class CommandEncoder {
 public:
  /// Encodes one command. MODE_DELTA_F commands are sent as left = collective + delta_f/2,
  /// right = collective - delta_f/2; MODE_LEFT_RIGHT commands send their left/right pair. The
  /// frames carry cmd.rolling_counter (modulo 16) and the low 16 bits of cmd.seq.
  std::array<can_frame, kCommandFrames.size()> encode(const nimble::actuator_command_t& cmd);

  /// Counters since construction.
  const EncodeStats& stats() const { return stats_; }

 private:
  EncodeStats stats_;
};

/// actuator_feedback_t -> kFbMotor, kFbServo, kFbStatus, with the encoder's own rolling counter.
class FeedbackEncoder {
 public:
  /// Encodes one feedback message with the current counter, then advances the counter.
  /// cmd_seq / cmd_age_us of -1 ("no command yet") are sent as FbCmdAge = kCmdAgeNoCommandRaw.
  std::array<can_frame, kFeedbackFrames.size()> encode(const nimble::actuator_feedback_t& fb);

  /// Counter (0..15) that the next encode() uses.
  uint8_t next_counter() const { return counter_; }
  /// Counters since construction.
  const EncodeStats& stats() const { return stats_; }

 private:
  EncodeStats stats_;
  uint8_t counter_ = 0;
};

/// What a decoder did with one frame.
enum class DecodeResult : uint8_t {
  kAccepted,         ///< valid frame, stored; its message still lacks frames
  kMessageComplete,  ///< valid frame that completed a message: the output was written
  kUnknownId,        ///< identifier not one of this decoder's frames (also extended/remote frames)
  kWrongLength,      ///< data length (DLC) differs from the layout
  kBadChecksum,      ///< CRC-8 mismatch
  kStaleCounter,     ///< rolling counter repeated or older than the last accepted one
  kOutOfRange,       ///< a signal's raw value lies outside its documented range
  kErrorFrame,       ///< CAN_ERR_FLAG set: an error frame (see error_frame.h), not data
};

/// Short name of a result, e.g. "bad_checksum".
const char* to_string(DecodeResult result);

/// Counters of a decoder, one per result; frames with any other result than kAccepted or
/// kMessageComplete were dropped.
struct DecodeStats {
  uint64_t frames_accepted = 0;      ///< kAccepted + kMessageComplete
  uint64_t messages = 0;             ///< kMessageComplete
  uint64_t unknown_id = 0;           ///< kUnknownId
  uint64_t wrong_length = 0;         ///< kWrongLength
  uint64_t bad_checksum = 0;         ///< kBadChecksum
  uint64_t stale_counter = 0;        ///< kStaleCounter
  uint64_t out_of_range = 0;         ///< kOutOfRange
  uint64_t error_frames = 0;         ///< kErrorFrame
  uint64_t counter_gaps = 0;         ///< frames missing between accepted counters (lost frames)
  uint64_t incomplete_messages = 0;  ///< messages abandoned because a newer frame replaced a part

  /// Frames dropped for any reason.
  uint64_t dropped() const {
    return unknown_id + wrong_length + bad_checksum + stale_counter + out_of_range + error_frames;
  }
};

/// Per-identifier rolling-counter check and assembly of one message from its frames (used by the
/// decoders; exposed for tests).
class FrameAssembler {
 public:
  /// Most frames one message may have.
  static constexpr std::size_t kMaxFrames = 4;

  /// An assembler for messages of `frame_count` frames (1..kMaxFrames).
  explicit FrameAssembler(std::size_t frame_count);
  /// Counter check for frame `index`: true if `counter` is 1..kCounterMaxAdvance ahead of the last
  /// accepted one (or the first); adds skipped counters to stats.counter_gaps.
  bool accept_counter(std::size_t index, uint8_t counter, DecodeStats& stats);
  /// Records that frame `index` with `counter` was stored; true if all frames now share one
  /// counter (the message is complete and its parts are consumed). A stored part that is replaced
  /// before its message completed counts as stats.incomplete_messages.
  bool store(std::size_t index, uint8_t counter, DecodeStats& stats);
  /// Forgets all counters and parts.
  void reset();

 private:
  std::size_t frame_count_;
  std::array<int, kMaxFrames> last_counter_{};     // -1: none yet
  std::array<int, kMaxFrames> pending_counter_{};  // -1: no part stored
};

/// CAN frames -> actuator_command_t.
class CommandDecoder {
 public:
  /// Validates and stores one frame. On kMessageComplete, `*out` holds the command: seq is
  /// reconstructed from its low 16 bits (nearest to the previous one), utime is 0 and source is
  /// empty (the caller stamps both), delta_f and collective are derived from left/right.
  DecodeResult decode(const can_frame& frame, nimble::actuator_command_t* out);

  /// Counters since construction.
  const DecodeStats& stats() const { return stats_; }
  /// Forgets counters and partial messages (e.g. after the sender restarted).
  void reset();

 private:
  DecodeStats stats_;
  FrameAssembler assembler_{kCommandFrames.size()};
  nimble::actuator_command_t pending_{};
  int64_t last_seq_ = -1;
};

/// CAN frames -> actuator_feedback_t.
class FeedbackDecoder {
 public:
  /// Validates and stores one frame. On kMessageComplete, `*out` holds the feedback: cmd_seq is
  /// reconstructed from its low 16 bits, utime and seq are 0 (the caller stamps them), delta_f is
  /// left - right.
  DecodeResult decode(const can_frame& frame, nimble::actuator_feedback_t* out);

  /// Counters since construction.
  const DecodeStats& stats() const { return stats_; }
  /// Forgets counters and partial messages.
  void reset();

 private:
  DecodeStats stats_;
  FrameAssembler assembler_{kFeedbackFrames.size()};
  nimble::actuator_feedback_t pending_{};
  int64_t last_cmd_seq_ = -1;
};

/// The 64-bit sequence number nearest to `previous` whose low 16 bits are `low16`
/// (`previous` < 0: no previous value, returns `low16`).
int64_t unwrap_seq16(int64_t previous, uint16_t low16);

}  // namespace nimble::can
