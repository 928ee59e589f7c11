// Unit tests of the CAN codec: CRC, signal packing, command/feedback round trips, saturation and
// every decode result. No CAN interface needed.

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

#include <catch2/catch.hpp>

#include "can_bridge/codec.h"
#include "can_bridge/crc8.h"
#include "can_bridge/frame_layout.h"
#include "can_bridge/signal_codec.h"

using namespace nimble::can;
using nimble::actuator_command_t;
using nimble::actuator_feedback_t;

namespace {

actuator_command_t command(int64_t seq, int8_t counter) {
  actuator_command_t c{};
  c.utime = 1000 * seq;
  c.seq = seq;
  c.mode = actuator_command_t::MODE_LEFT_RIGHT;
  c.flap_freq_left_radps = 110.25;
  c.flap_freq_right_radps = 103.5;
  c.delta_f_radps = c.flap_freq_left_radps - c.flap_freq_right_radps;
  c.flap_freq_collective_radps = 0.5 * (c.flap_freq_left_radps + c.flap_freq_right_radps);
  c.throttle_pct = 62.5;
  c.dihedral_rad = -0.1234;
  c.wing_root_rad = 0.25;
  c.rolling_counter = counter;
  c.source = "test";
  return c;
}

actuator_feedback_t feedback(int64_t cmd_seq) {
  actuator_feedback_t f{};
  f.flap_freq_left_radps = 107.0;
  f.flap_freq_right_radps = 106.5;
  f.delta_f_radps = 0.5;
  f.dihedral_rad = 0.05;
  f.wing_root_rad = -0.02;
  f.throttle_pct = 40.0;
  f.cmd_seq = cmd_seq;
  f.cmd_age_us = 1953;
  f.safe_state = false;
  return f;
}

/// Decodes all frames; returns the result of the last one.
template <typename Decoder, typename Msg, std::size_t N>
DecodeResult feed(Decoder& d, const std::array<can_frame, N>& frames, Msg* out) {
  DecodeResult r = DecodeResult::kAccepted;
  for (const can_frame& f : frames) r = d.decode(f, out);
  return r;
}

/// Recomputes the CRC after a test changed a frame's payload on purpose.
void reseal(can_frame& f) { f.data[kCrcByte] = frame_crc(f.can_id & CAN_SFF_MASK, f.data, kCrcByte); }

constexpr double kFreqLsb = 0.01, kServoLsb = 0.0001;

}  // namespace

TEST_CASE("CRC-8/SAE-J1850 has its catalogue check value and covers the identifier", "[crc]") {
  const uint8_t check[] = {'1', '2', '3', '4', '5', '6', '7', '8', '9'};
  CHECK(crc8_sae_j1850(check, sizeof check) == 0x4B);
  const uint8_t empty[1] = {0};
  CHECK(crc8_sae_j1850(empty, 0) == 0x00);  // init 0xFF ^ xorout 0xFF
  const uint8_t payload[7] = {1, 2, 3, 4, 5, 6, 7};
  CHECK(frame_crc(0x101, payload, 7) != frame_crc(0x102, payload, 7));
  // frame_crc is the plain CRC over [id low, id high, payload...]
  const uint8_t joined[9] = {0x01, 0x01, 1, 2, 3, 4, 5, 6, 7};
  CHECK(frame_crc(0x101, payload, 7) == crc8_sae_j1850(joined, 9));
}

TEST_CASE("signals pack little-endian and sign-extend", "[signal]") {
  uint8_t d[8] = {};
  pack_signal(d, 8, kCmdDihedral, -1234);  // 0xFB2E
  CHECK(d[0] == 0x2E);
  CHECK(d[1] == 0xFB);
  CHECK(unpack_signal(d, 8, kCmdDihedral) == -1234);
  pack_signal(d, 8, kFbCmdAge, 0xABCDEF);
  CHECK(unpack_signal(d, 8, kFbCmdAge) == 0xABCDEF);
  CHECK(d[2] == 0xEF);
  CHECK(d[3] == 0xCD);
  CHECK(d[4] == 0xAB);
  // every signal round-trips its extreme raw values without touching other bits
  for (const SignalSpec& s : kAllSignals) {
    for (int64_t raw : {raw_min(s), raw_max(s)}) {
      uint8_t buf[8];
      std::memset(buf, 0xA5, sizeof buf);
      uint8_t before[8];
      std::memcpy(before, buf, sizeof buf);
      pack_signal(buf, 8, s, raw);
      INFO(s.name << " raw " << raw);
      CHECK(unpack_signal(buf, 8, s) == raw);
      for (unsigned bit = 0; bit < 64; ++bit) {
        if (bit >= s.start_bit && bit < s.start_bit + s.length_bits) continue;
        CHECK(((buf[bit / 8] >> (bit % 8)) & 1) == ((before[bit / 8] >> (bit % 8)) & 1));
      }
    }
  }
}

TEST_CASE("a command frame has the documented bytes", "[layout]") {
  actuator_command_t c = command(0x1234, 3);
  c.flap_freq_left_radps = 100.0;  // 10000 = 0x2710
  c.flap_freq_right_radps = 90.0;  // 9000 = 0x2328
  c.throttle_pct = 50.0;           // 5000 = 0x1388
  c.dihedral_rad = -0.1234;        // -1234 = 0xFB2E
  c.wing_root_rad = 0.5;           // 5000 = 0x1388
  CommandEncoder enc;
  const auto frames = enc.encode(c);
  REQUIRE(frames[0].can_id == 0x101);
  REQUIRE(frames[1].can_id == 0x102);
  const std::vector<uint8_t> flap(frames[0].data, frames[0].data + 7);
  CHECK(flap == std::vector<uint8_t>{0x10, 0x27, 0x28, 0x23, 0x88, 0x13, 0x30});
  CHECK(frames[0].data[7] == frame_crc(0x101, frames[0].data, 7));
  const std::vector<uint8_t> servo(frames[1].data, frames[1].data + 7);
  CHECK(servo == std::vector<uint8_t>{0x2E, 0xFB, 0x88, 0x13, 0x34, 0x12, 0x30});
  CHECK(frames[1].data[7] == frame_crc(0x102, frames[1].data, 7));
  for (const can_frame& f : frames) CHECK(f.len == 8);
  c.mode = actuator_command_t::MODE_DELTA_F;
  c.flap_freq_collective_radps = 95.0;
  c.delta_f_radps = 10.0;
  const auto delta = enc.encode(c);
  CHECK(delta[0].data[6] == 0x31);  // mode 1, counter 3
  CHECK(std::vector<uint8_t>(delta[0].data, delta[0].data + 4) == std::vector<uint8_t>{0x10, 0x27, 0x28, 0x23});
}

TEST_CASE("commands round-trip through the frames", "[roundtrip]") {
  CommandEncoder enc;
  CommandDecoder dec;
  std::mt19937 rng(42);
  std::uniform_real_distribution<double> freq(0.0, 400.0), thr(0.0, 100.0), servo(-1.0, 1.0);
  int64_t seq = 65500;  // crosses the 16-bit wrap of CmdSeq
  for (int i = 0; i < 200; ++i, ++seq) {
    actuator_command_t c = command(seq, static_cast<int8_t>(seq % 16));
    c.mode = (i % 2) ? actuator_command_t::MODE_DELTA_F : actuator_command_t::MODE_LEFT_RIGHT;
    const double left = freq(rng), right = freq(rng);
    c.flap_freq_left_radps = left;
    c.flap_freq_right_radps = right;
    c.delta_f_radps = left - right;
    c.flap_freq_collective_radps = 0.5 * (left + right);
    c.throttle_pct = thr(rng);
    c.dihedral_rad = servo(rng);
    c.wing_root_rad = servo(rng);
    if (i == 0) {  // the documented range ends
      c.flap_freq_left_radps = 0.0;
      c.flap_freq_right_radps = 400.0;
      c.throttle_pct = 100.0;
      c.dihedral_rad = -1.0;
      c.wing_root_rad = 1.0;
      c.mode = actuator_command_t::MODE_LEFT_RIGHT;
      c.delta_f_radps = -400.0;
      c.flap_freq_collective_radps = 200.0;
    }
    actuator_command_t out{};
    INFO("message " << i);
    REQUIRE(feed(dec, enc.encode(c), &out) == DecodeResult::kMessageComplete);
    CHECK(out.seq == seq);
    CHECK(out.mode == c.mode);
    CHECK(out.rolling_counter == c.rolling_counter);
    CHECK(out.flap_freq_left_radps == Approx(c.flap_freq_left_radps).margin(kFreqLsb));
    CHECK(out.flap_freq_right_radps == Approx(c.flap_freq_right_radps).margin(kFreqLsb));
    CHECK(out.delta_f_radps == Approx(c.delta_f_radps).margin(2 * kFreqLsb));
    CHECK(out.flap_freq_collective_radps == Approx(c.flap_freq_collective_radps).margin(kFreqLsb));
    CHECK(out.throttle_pct == Approx(c.throttle_pct).margin(0.01));
    CHECK(out.dihedral_rad == Approx(c.dihedral_rad).margin(kServoLsb));
    CHECK(out.wing_root_rad == Approx(c.wing_root_rad).margin(kServoLsb));
    CHECK(out.utime == 0);
    CHECK(out.source.empty());
  }
  CHECK(enc.stats().messages == 200);
  CHECK(enc.stats().saturated_values == 0);
  CHECK(dec.stats().messages == 200);
  CHECK(dec.stats().frames_accepted == 400);
  CHECK(dec.stats().dropped() == 0);
  CHECK(dec.stats().counter_gaps == 0);
}

TEST_CASE("feedback round-trips through the frames", "[roundtrip]") {
  FeedbackEncoder enc;
  FeedbackDecoder dec;
  actuator_feedback_t out{};

  actuator_feedback_t none = feedback(-1);
  none.cmd_age_us = -1;
  none.safe_state = true;
  REQUIRE(feed(dec, enc.encode(none), &out) == DecodeResult::kMessageComplete);
  CHECK(out.cmd_seq == -1);
  CHECK(out.cmd_age_us == -1);
  CHECK(out.safe_state);

  for (int64_t cmd_seq : {int64_t{65534}, int64_t{65535}, int64_t{65536}, int64_t{70000}}) {
    actuator_feedback_t f = feedback(cmd_seq);
    f.cmd_age_us = cmd_seq % 5000;
    f.safe_state = (cmd_seq % 2) == 0;
    f.throttle_pct = (cmd_seq % 2) ? -12.34 : 99.99;  // deviation from trim: signed
    INFO("cmd_seq " << cmd_seq);
    REQUIRE(feed(dec, enc.encode(f), &out) == DecodeResult::kMessageComplete);
    CHECK(out.cmd_seq == cmd_seq);
    CHECK(out.cmd_age_us == f.cmd_age_us);
    CHECK(out.safe_state == f.safe_state);
    CHECK(out.flap_freq_left_radps == Approx(f.flap_freq_left_radps).margin(kFreqLsb));
    CHECK(out.flap_freq_right_radps == Approx(f.flap_freq_right_radps).margin(kFreqLsb));
    CHECK(out.delta_f_radps == Approx(f.flap_freq_left_radps - f.flap_freq_right_radps).margin(2 * kFreqLsb));
    CHECK(out.throttle_pct == Approx(f.throttle_pct).margin(0.01));
    CHECK(out.dihedral_rad == Approx(f.dihedral_rad).margin(kServoLsb));
    CHECK(out.wing_root_rad == Approx(f.wing_root_rad).margin(kServoLsb));
  }
  CHECK(enc.next_counter() == 5);
  CHECK(dec.stats().messages == 5);
  CHECK(dec.stats().dropped() == 0);
}

TEST_CASE("the encoders clamp out-of-range values to the documented range and count them", "[saturation]") {
  CommandEncoder enc;
  CommandDecoder dec;
  actuator_command_t c = command(1, 1);
  c.flap_freq_left_radps = -5.0;
  c.flap_freq_right_radps = 1000.0;
  c.throttle_pct = 150.0;
  c.dihedral_rad = 2.0;
  c.wing_root_rad = -3.0;
  actuator_command_t out{};
  REQUIRE(feed(dec, enc.encode(c), &out) == DecodeResult::kMessageComplete);
  CHECK(enc.stats().saturated_values == 5);
  CHECK(out.flap_freq_left_radps == 0.0);
  CHECK(out.flap_freq_right_radps == Approx(400.0));
  CHECK(out.throttle_pct == Approx(100.0));
  CHECK(out.dihedral_rad == Approx(1.0));
  CHECK(out.wing_root_rad == Approx(-1.0));

  SECTION("non-finite values are sent as 0") {
    c = command(2, 2);
    c.flap_freq_left_radps = std::nan("");
    c.dihedral_rad = INFINITY;
    REQUIRE(feed(dec, enc.encode(c), &out) == DecodeResult::kMessageComplete);
    CHECK(enc.stats().non_finite_values == 2);
    CHECK(out.flap_freq_left_radps == 0.0);
    CHECK(out.dihedral_rad == 0.0);
  }
  SECTION("an unknown mode is sent as MODE_LEFT_RIGHT, a counter outside 0..15 modulo 16") {
    c = command(2, 20);  // 20 % 16 = 4
    c.mode = 7;
    REQUIRE(feed(dec, enc.encode(c), &out) == DecodeResult::kMessageComplete);
    CHECK(enc.stats().invalid_modes == 1);
    CHECK(enc.stats().invalid_counters == 1);
    CHECK(out.mode == actuator_command_t::MODE_LEFT_RIGHT);
    CHECK(out.rolling_counter == 4);
    CHECK(out.flap_freq_left_radps == Approx(c.flap_freq_left_radps).margin(kFreqLsb));
  }
  SECTION("a DELTA_F command whose wing frequencies leave the range is clamped per wing") {
    c = command(2, 2);
    c.mode = actuator_command_t::MODE_DELTA_F;
    c.flap_freq_collective_radps = 399.0;
    c.delta_f_radps = 10.0;  // left 404 -> 400
    REQUIRE(feed(dec, enc.encode(c), &out) == DecodeResult::kMessageComplete);
    CHECK(enc.stats().saturated_values == 6);
    CHECK(out.flap_freq_left_radps == Approx(400.0));
    CHECK(out.flap_freq_right_radps == Approx(394.0));
  }
  SECTION("feedback command age") {
    FeedbackEncoder fenc;
    FeedbackDecoder fdec;
    actuator_feedback_t f = feedback(5);
    f.cmd_age_us = int64_t{1} << 40;
    actuator_feedback_t fout{};
    REQUIRE(feed(fdec, fenc.encode(f), &fout) == DecodeResult::kMessageComplete);
    CHECK(fout.cmd_age_us == kCmdAgeMax_us);
    f.cmd_age_us = -7;  // negative age with a valid command
    REQUIRE(feed(fdec, fenc.encode(f), &fout) == DecodeResult::kMessageComplete);
    CHECK(fout.cmd_age_us == 0);
    CHECK(fenc.stats().saturated_values == 2);
  }
}

TEST_CASE("the decoders give a result for every kind of bad frame and never an exception", "[decode]") {
  CommandEncoder enc;
  CommandDecoder dec;
  actuator_command_t out{};
  const auto good = enc.encode(command(10, 5));

  SECTION("unknown identifier, extended and remote frames") {
    can_frame f = good[0];
    f.can_id = 0x123;
    CHECK(dec.decode(f, &out) == DecodeResult::kUnknownId);
    f.can_id = 0x101 | CAN_EFF_FLAG;
    CHECK(dec.decode(f, &out) == DecodeResult::kUnknownId);
    f.can_id = 0x101 | CAN_RTR_FLAG;
    CHECK(dec.decode(f, &out) == DecodeResult::kUnknownId);
    FeedbackDecoder fdec;  // a command frame is unknown to the feedback decoder
    actuator_feedback_t fout{};
    CHECK(fdec.decode(good[0], &fout) == DecodeResult::kUnknownId);
    CHECK(dec.stats().unknown_id == 3);
    CHECK(fdec.stats().unknown_id == 1);
  }
  SECTION("wrong length") {
    can_frame f = good[0];
    f.len = 7;
    CHECK(dec.decode(f, &out) == DecodeResult::kWrongLength);
    f.len = 0;
    CHECK(dec.decode(f, &out) == DecodeResult::kWrongLength);
    CHECK(dec.stats().wrong_length == 2);
  }
  SECTION("bad checksum: payload bit flipped, CRC byte changed, payload under another identifier") {
    can_frame f = good[0];
    f.data[0] ^= 0x01;
    CHECK(dec.decode(f, &out) == DecodeResult::kBadChecksum);
    f = good[1];
    f.data[7] ^= 0x80;
    CHECK(dec.decode(f, &out) == DecodeResult::kBadChecksum);
    f = good[1];
    f.can_id = 0x101;
    CHECK(dec.decode(f, &out) == DecodeResult::kBadChecksum);
    CHECK(dec.stats().bad_checksum == 3);
  }
  SECTION("raw value outside the documented range") {
    can_frame f = good[0];
    pack_signal(f.data, 8, kCmdThrottle, 0xFFFF);  // 655.35 %
    reseal(f);
    CHECK(dec.decode(f, &out) == DecodeResult::kOutOfRange);
    f = good[0];
    pack_signal(f.data, 8, kCmdMode, 3);
    reseal(f);
    CHECK(dec.decode(f, &out) == DecodeResult::kOutOfRange);
    f = good[1];
    pack_signal(f.data, 8, kCmdDihedral, -20000);  // -2 rad
    reseal(f);
    CHECK(dec.decode(f, &out) == DecodeResult::kOutOfRange);
    CHECK(dec.stats().out_of_range == 3);
  }
  SECTION("error frame") {
    can_frame f{};
    f.can_id = CAN_ERR_FLAG | 0x40;
    f.len = 8;
    CHECK(dec.decode(f, &out) == DecodeResult::kErrorFrame);
    CHECK(dec.stats().error_frames == 1);
  }
  SECTION("repeated and older counters are stale; a jump is accepted and counted as a gap") {
    REQUIRE(feed(dec, good, &out) == DecodeResult::kMessageComplete);
    CHECK(dec.decode(good[0], &out) == DecodeResult::kStaleCounter);  // repeated
    CHECK(dec.decode(good[1], &out) == DecodeResult::kStaleCounter);
    const auto older = enc.encode(command(9, 4));
    CHECK(dec.decode(older[0], &out) == DecodeResult::kStaleCounter);
    const auto far_behind = enc.encode(command(3, 13));  // 5 - 13 = -8 mod 16 = 8 ahead: too far
    CHECK(dec.decode(far_behind[0], &out) == DecodeResult::kStaleCounter);
    CHECK(dec.stats().stale_counter == 4);
    const auto jump = enc.encode(command(13, 8));  // 3 ahead: counters 6 and 7 lost
    CHECK(feed(dec, jump, &out) == DecodeResult::kMessageComplete);
    CHECK(out.seq == 13);
    CHECK(dec.stats().counter_gaps == 4);  // 2 per frame identifier
    // wrap 15 -> 0
    CHECK(feed(dec, enc.encode(command(20, 15)), &out) == DecodeResult::kMessageComplete);
    CHECK(feed(dec, enc.encode(command(21, 0)), &out) == DecodeResult::kMessageComplete);
    CHECK(out.rolling_counter == 0);
  }
  SECTION("after every kind of bad frame the decoder still completes the next good message") {
    can_frame bad = good[0];
    bad.data[3] ^= 0x10;
    CHECK(dec.decode(bad, &out) == DecodeResult::kBadChecksum);
    bad = good[0];
    bad.len = 3;
    CHECK(dec.decode(bad, &out) == DecodeResult::kWrongLength);
    out = actuator_command_t{};
    CHECK(feed(dec, good, &out) == DecodeResult::kMessageComplete);
    CHECK(out.seq == 10);
  }
}

TEST_CASE("messages are assembled from frames with the same counter", "[decode]") {
  CommandEncoder enc;
  CommandDecoder dec;
  actuator_command_t out{};
  const auto a = enc.encode(command(1, 1));
  const auto b = enc.encode(command(2, 2));
  const auto c = enc.encode(command(3, 3));

  CHECK(dec.decode(a[1], &out) == DecodeResult::kAccepted);  // servo first
  CHECK(dec.decode(a[0], &out) == DecodeResult::kMessageComplete);
  CHECK(out.seq == 1);
  CHECK(dec.decode(b[0], &out) == DecodeResult::kAccepted);  // b's servo frame is lost
  CHECK(dec.decode(c[1], &out) == DecodeResult::kAccepted);  // c's servo does not complete b
  CHECK(dec.decode(c[0], &out) == DecodeResult::kMessageComplete);
  CHECK(out.seq == 3);
  CHECK(dec.stats().messages == 2);
  CHECK(dec.stats().incomplete_messages == 1);
  CHECK(dec.stats().counter_gaps == 1);  // servo counter 1 -> 3
}

TEST_CASE("random frames never crash the decoders and every frame is counted", "[decode][fuzz]") {
  std::mt19937 rng(7);
  std::uniform_int_distribution<int> byte(0, 255), pick(0, 9);
  CommandDecoder cdec;
  FeedbackDecoder fdec;
  CommandEncoder cenc;
  FeedbackEncoder fenc;
  const uint32_t ids[] = {0x101, 0x102, 0x181, 0x182, 0x183, 0x123, 0x7FF, 0x101 | CAN_EFF_FLAG};
  const int n = 20000;
  uint64_t completes = 0;
  for (int i = 0; i < n; ++i) {
    can_frame f{};
    if (pick(rng) < 3) {  // a valid frame now and then, sometimes corrupted
      f = (i % 2) ? cenc.encode(command(i, static_cast<int8_t>(i % 16)))[(i / 2) % 2]
                  : fenc.encode(feedback(i))[(i / 2) % 3];
      if (pick(rng) < 3) f.data[byte(rng) % 8] ^= static_cast<uint8_t>(1 + byte(rng) % 255);
    } else {
      f.can_id = ids[byte(rng) % 8];
      if (pick(rng) == 0) f.can_id |= CAN_ERR_FLAG;
      f.len = static_cast<uint8_t>(byte(rng) % 9);
      for (auto& d : f.data) d = static_cast<uint8_t>(byte(rng));
      if (pick(rng) < 5) reseal(f);
    }
    actuator_command_t cout{};
    actuator_feedback_t fout{};
    completes += cdec.decode(f, &cout) == DecodeResult::kMessageComplete;
    completes += fdec.decode(f, &fout) == DecodeResult::kMessageComplete;
  }
  for (const DecodeStats* s : {&cdec.stats(), &fdec.stats()}) {
    CHECK(s->frames_accepted + s->dropped() == static_cast<uint64_t>(n));
  }
  CHECK(cdec.stats().messages + fdec.stats().messages == completes);
}

TEST_CASE("16-bit sequence numbers unwrap to the nearest 64-bit value", "[seq]") {
  CHECK(unwrap_seq16(-1, 17) == 17);
  CHECK(unwrap_seq16(65535, 0) == 65536);
  CHECK(unwrap_seq16(65536, 65535) == 65535);
  CHECK(unwrap_seq16(200000, (200000 + 5) & 0xFFFF) == 200005);
  CHECK(unwrap_seq16(200000, (200000 - 5) & 0xFFFF) == 199995);
  CHECK(unwrap_seq16(10, 65530) == 65530);  // would be negative: no unwrap below zero
}
