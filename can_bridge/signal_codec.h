#pragma once
/// Bit-level packing and scaling of the layout's signals (frame_layout.h).
///
/// Works on a byte buffer of any length, so the same code serves classical CAN (8 bytes) and a
/// CAN FD layout (up to 64 bytes).

#include <cstddef>
#include <cstdint>

#include "can_bridge/frame_layout.h"

namespace nimble::can {

/// Writes the low `length_bits` bits of `raw` little-endian at `start_bit` of `data`.
/// Bits outside the buffer are not written.
void pack_bits_le(uint8_t* data, std::size_t length_bytes, unsigned start_bit, unsigned length_bits, uint64_t raw);

/// Reads `length_bits` bits little-endian from `start_bit` of `data` (zero-extended).
uint64_t unpack_bits_le(const uint8_t* data, std::size_t length_bytes, unsigned start_bit, unsigned length_bits);

/// Smallest and largest raw value of a signal's documented physical range.
int64_t raw_min(const SignalSpec& signal);
int64_t raw_max(const SignalSpec& signal);

/// Result of converting a physical value to raw.
struct ToRawResult {
  int64_t raw = 0;          ///< raw value inside [raw_min, raw_max]
  bool saturated = false;   ///< the value was outside [min, max] and was clamped
  bool non_finite = false;  ///< the value was NaN or infinite and was replaced by 0 (clamped)
};

/// Physical -> raw: clamps to the documented range, rounds to the nearest step. Never throws.
ToRawResult to_raw(const SignalSpec& signal, double physical);

/// Raw -> physical (raw * factor + offset).
double to_physical(const SignalSpec& signal, int64_t raw);

/// Packs `raw` (two's complement for signed signals) into `data` at the signal's position.
void pack_signal(uint8_t* data, std::size_t length_bytes, const SignalSpec& signal, int64_t raw);

/// Reads the signal's raw value from `data` (sign-extended for signed signals).
int64_t unpack_signal(const uint8_t* data, std::size_t length_bytes, const SignalSpec& signal);

/// True if `raw` lies inside the signal's documented range.
bool raw_in_range(const SignalSpec& signal, int64_t raw);

}  // namespace nimble::can
