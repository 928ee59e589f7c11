// Fuzz target: the CAN frame decoders (can_bridge/codec.h), the signal unpacking and scaling
// (signal_codec.h) and the error-frame decoder (error_frame.h).
//
// An input is a sequence of 15-byte frames: identifier (4 bytes, little endian, flags
// included), length, control byte, 8 data bytes, and one byte of a physical value's seed. Bit 0
// of the control byte writes the frame's correct CRC into byte 7 before decoding, so that inputs
// get past the checksum to the counter, range and assembly logic. Every frame goes through a
// command decoder, a feedback decoder and the error-frame decoder.
//
// Properties: every frame is counted exactly once by each decoder (accepted or dropped for one
// reason); a completed message carries finite values inside the layout's documented ranges; a
// completed command re-encodes (CommandEncoder) to frames that a fresh decoder takes back to the
// same values; to_raw() of any value lies inside the signal's raw range.

#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "can_bridge/codec.h"
#include "can_bridge/crc8.h"
#include "can_bridge/error_frame.h"
#include "can_bridge/frame_layout.h"
#include "can_bridge/signal_codec.h"
#include "fuzz/fuzz_support.h"

using namespace nimble::can;
using nimble::fuzz::require;

namespace {

constexpr std::size_t kRecord = 15;

uint64_t total(const DecodeStats& s) { return s.frames_accepted + s.dropped(); }

bool in_signal_range(const SignalSpec& s, double value) {
  // The decoded value is raw * factor + offset of an in-range raw value: inside [min, max]
  // up to the rounding of the scaling.
  const double slack = std::abs(s.factor) * 1e-6 + 1e-12;
  return std::isfinite(value) && value >= s.min - slack && value <= s.max + slack;
}

/// The five actuator values of a decoded command or feedback (`what`) inside their signals'
/// ranges: left and right flapping frequency, throttle, dihedral, wing root.
template <typename Message>
void check_in_range(const Message& m, const std::array<const SignalSpec*, 5>& signals, const std::string& what) {
  const double values[] = {m.flap_freq_left_radps, m.flap_freq_right_radps, m.throttle_pct, m.dihedral_rad,
                           m.wing_root_rad};
  const char* names[] = {"left flapping frequency", "right flapping frequency", "throttle", "dihedral", "wing root"};
  for (std::size_t i = 0; i < signals.size(); ++i) {
    require(in_signal_range(*signals[i], values[i]), "decoded " + what + " " + names[i] + " out of range");
  }
}

void check_command(const nimble::actuator_command_t& c) {
  check_in_range(c, {&kCmdFlapFreqLeft, &kCmdFlapFreqRight, &kCmdThrottle, &kCmdDihedral, &kCmdWingRoot}, "command");
  require(c.mode == nimble::actuator_command_t::MODE_LEFT_RIGHT || c.mode == nimble::actuator_command_t::MODE_DELTA_F,
          "decoded mode " + std::to_string(c.mode) + " is not a MODE_*");
  require(c.seq >= 0, "decoded seq is negative");
  require(c.rolling_counter >= 0 && c.rolling_counter < 16, "decoded rolling counter outside 0..15");

  // Encode it again and decode with a fresh decoder: the same values come back.
  CommandEncoder encoder;
  CommandDecoder decoder;
  nimble::actuator_command_t again{};
  DecodeResult last = DecodeResult::kAccepted;
  for (const can_frame& f : encoder.encode(c)) last = decoder.decode(f, &again);
  require(last == DecodeResult::kMessageComplete,
          std::string("a decoded command, encoded again, does not decode: ") + to_string(last));
  require(encoder.stats().saturated_values == 0 && encoder.stats().non_finite_values == 0,
          "a decoded command needs clamping to be encoded again");
  require(std::abs(again.flap_freq_left_radps - c.flap_freq_left_radps) <= kCmdFlapFreqLeft.factor / 2 &&
              std::abs(again.flap_freq_right_radps - c.flap_freq_right_radps) <= kCmdFlapFreqRight.factor / 2 &&
              std::abs(again.throttle_pct - c.throttle_pct) <= kCmdThrottle.factor / 2 &&
              std::abs(again.dihedral_rad - c.dihedral_rad) <= kCmdDihedral.factor / 2 &&
              std::abs(again.wing_root_rad - c.wing_root_rad) <= kCmdWingRoot.factor / 2 && again.mode == c.mode &&
              (again.seq & 0xFFFF) == (c.seq & 0xFFFF),
          "a decoded command does not survive encoding and decoding again");
}

void check_feedback(const nimble::actuator_feedback_t& fb) {
  check_in_range(fb, {&kFbFlapFreqLeft, &kFbFlapFreqRight, &kFbThrottle, &kFbDihedral, &kFbWingRoot}, "feedback");
  require((fb.cmd_seq == -1) == (fb.cmd_age_us == -1), "feedback: cmd_seq and cmd_age_us disagree on 'no command'");
  require(fb.cmd_age_us >= -1 && fb.cmd_age_us <= kCmdAgeMax_us, "decoded command age out of range");
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  CommandDecoder commands;
  FeedbackDecoder feedback;
  uint64_t frames = 0;
  for (std::size_t pos = 0; pos + kRecord <= size; pos += kRecord) {
    const uint8_t* r = data + pos;
    can_frame f{};
    std::memcpy(&f.can_id, r, 4);
    f.len = static_cast<uint8_t>(r[4] % (CAN_MAX_DLEN + 1));
    const uint8_t control = r[5];
    std::memcpy(f.data, r + 6, CAN_MAX_DLEN);
    if (control & 1) f.data[kCrcByte] = frame_crc(f.can_id & CAN_SFF_MASK, f.data, kCrcByte);
    ++frames;

    nimble::actuator_command_t cmd{};
    if (commands.decode(f, &cmd) == DecodeResult::kMessageComplete) check_command(cmd);
    nimble::actuator_feedback_t fb{};
    if (feedback.decode(f, &fb) == DecodeResult::kMessageComplete) check_feedback(fb);
    require(total(commands.stats()) == frames, "the command decoder did not count every frame once");
    require(total(feedback.stats()) == frames, "the feedback decoder did not count every frame once");

    const ErrorFrameInfo info = decode_error_frame(f);
    require(is_error_frame(f) || info.error_class == 0, "a data frame decoded as an error frame");
    require(!info.description.empty(), "an error frame decoded without a description");

    // Signal scaling on the frame's bytes and on a value made of them.
    double value = 0;
    std::memcpy(&value, f.data, sizeof value);
    if (r[14] & 1) value = static_cast<double>(static_cast<int16_t>(f.data[0] | (f.data[1] << 8))) * 0.013;
    for (const SignalSpec& s : kAllSignals) {
      const ToRawResult tr = to_raw(s, value);
      require(tr.raw >= raw_min(s) && tr.raw <= raw_max(s) && raw_in_range(s, tr.raw),
              std::string("to_raw(") + s.name + ", " + std::to_string(value) + ") left the raw range");
      uint8_t buffer[CAN_MAX_DLEN] = {};
      pack_signal(buffer, sizeof buffer, s, tr.raw);
      require(unpack_signal(buffer, sizeof buffer, s) == tr.raw, std::string(s.name) + ": pack/unpack differ");
      (void)unpack_signal(f.data, f.len, s);
    }
  }
  return 0;
}
