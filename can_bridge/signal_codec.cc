#include "can_bridge/signal_codec.h"

#include <algorithm>
#include <cmath>

namespace nimble::can {

void pack_bits_le(uint8_t* data, std::size_t length_bytes, unsigned start_bit, unsigned length_bits, uint64_t raw) {
  for (unsigned i = 0; i < length_bits; ++i) {
    const unsigned bit = start_bit + i;
    const std::size_t byte = bit / 8;
    if (byte >= length_bytes) return;
    const uint8_t mask = static_cast<uint8_t>(1u << (bit % 8));
    if ((raw >> i) & 1u) {
      data[byte] = static_cast<uint8_t>(data[byte] | mask);
    } else {
      data[byte] = static_cast<uint8_t>(data[byte] & ~mask);
    }
  }
}

uint64_t unpack_bits_le(const uint8_t* data, std::size_t length_bytes, unsigned start_bit, unsigned length_bits) {
  uint64_t raw = 0;
  for (unsigned i = 0; i < length_bits; ++i) {
    const unsigned bit = start_bit + i;
    const std::size_t byte = bit / 8;
    if (byte >= length_bytes) break;
    if ((data[byte] >> (bit % 8)) & 1u) raw |= uint64_t{1} << i;
  }
  return raw;
}

int64_t raw_min(const SignalSpec& s) { return std::llround((s.min - s.offset) / s.factor); }
int64_t raw_max(const SignalSpec& s) { return std::llround((s.max - s.offset) / s.factor); }

ToRawResult to_raw(const SignalSpec& s, double physical) {
  ToRawResult r;
  if (!std::isfinite(physical)) {
    r.non_finite = true;
    physical = 0.0;
  }
  if (physical < s.min || physical > s.max) {
    r.saturated = true;
    physical = std::clamp(physical, s.min, s.max);
  }
  r.raw = std::clamp<int64_t>(std::llround((physical - s.offset) / s.factor), raw_min(s), raw_max(s));
  return r;
}

double to_physical(const SignalSpec& s, int64_t raw) { return static_cast<double>(raw) * s.factor + s.offset; }

void pack_signal(uint8_t* data, std::size_t length_bytes, const SignalSpec& s, int64_t raw) {
  pack_bits_le(data, length_bytes, s.start_bit, s.length_bits, static_cast<uint64_t>(raw));
}

int64_t unpack_signal(const uint8_t* data, std::size_t length_bytes, const SignalSpec& s) {
  const uint64_t bits = unpack_bits_le(data, length_bytes, s.start_bit, s.length_bits);
  if (s.is_signed && s.length_bits < 64 && ((bits >> (s.length_bits - 1)) & 1u)) {
    return static_cast<int64_t>(bits | (~uint64_t{0} << s.length_bits));
  }
  return static_cast<int64_t>(bits);
}

bool raw_in_range(const SignalSpec& s, int64_t raw) { return raw >= raw_min(s) && raw <= raw_max(s); }

}  // namespace nimble::can
