#pragma once
/// Decoding a received LCM message without trusting it.
///
/// LCM 1.3.1's generated decoders check sizes but not everything:
///  - a string field whose encoded length is 0 makes them call std::string::assign(p, -1),
///    which throws;
///  - a variable-length array is resized to the count read from the bytes before any element
///    is read: a count of 10^9 in a 100-byte message allocates gigabytes;
///  - a string is taken with whatever its terminating byte holds and with NUL bytes inside,
///    which the encoder (strlen) cannot write back: the message decodes, but a node that copies
///    such a string into a message of its own (the run id into RIG_CLOCK) can no longer publish.
/// Every reader of messages from the bus or a log decodes through decode_exact(), so that such
/// bytes are one more malformed message, never an exception that ends a process, an allocation
/// out of proportion to the message, or a message that cannot be sent on.

#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

#include <nimble/run_control_t.hpp>
#include <nimble/timing_health_t.hpp>

namespace nimble::contract {

namespace detail {

/// Reads LCM's big-endian int32 at `*pos` and advances; false if the bytes end first.
inline bool read_int32(const uint8_t* p, int size, int64_t* pos, int64_t* value) {
  if (*pos < 0 || *pos + 4 > size) return false;
  const uint32_t u = (uint32_t{p[*pos]} << 24) | (uint32_t{p[*pos + 1]} << 16) | (uint32_t{p[*pos + 2]} << 8) |
                     uint32_t{p[*pos + 3]};
  *value = static_cast<int32_t>(u);
  *pos += 4;
  return true;
}

/// Skips an LCM string at `*pos` (int32 length with the NUL, then the bytes); false if it does
/// not fit.
inline bool skip_string(const uint8_t* p, int size, int64_t* pos) {
  int64_t length = 0;
  if (!read_int32(p, size, pos, &length) || length < 0) return false;
  *pos += length;
  return *pos <= size;
}

/// True if the array count at `pos` (after the fixed-size fields skipped so far) leaves room in
/// the message for that many elements of at least `min_element_bytes` each.
inline bool count_fits(const uint8_t* p, int size, int64_t pos, int64_t min_element_bytes) {
  int64_t count = 0;
  if (!read_int32(p, size, &pos, &count)) return true;  // too short: the decoder refuses it
  return count >= 0 && count <= (size - pos) / min_element_bytes;
}

constexpr int64_t kFingerprintBytes = 8;
constexpr int64_t kMinStringBytes = 5;  ///< int32 length and the NUL

/// True unless an array count of a T's bytes exceeds what the bytes can hold (see above). One
/// specialisation per type with a variable-length array, written from its .lcm file's field
/// order; functional.lcmtypes checks each against the encoder for several counts.
template <typename T>
inline bool array_counts_fit(const uint8_t*, int) {
  return true;
}

template <>
inline bool array_counts_fit<run_control_t>(const uint8_t* p, int size) {
  // utime, seq (int64), command, clock_mode (int8), t0_monotonic_ns, duration_ns (int64),
  // run_id (string), num_participants, participants[num_participants] (string).
  int64_t pos = kFingerprintBytes + 8 + 8 + 1 + 1 + 8 + 8;
  if (!skip_string(p, size, &pos)) return true;  // the decoder refuses it
  return count_fits(p, size, pos, kMinStringBytes);
}

template <>
inline bool array_counts_fit<timing_health_t>(const uint8_t* p, int size) {
  // utime, seq (int64), process (string), window_us (int64), loop_rate_hz (double), loop_count,
  // overruns (int64), jitter p50, p99, max (double), latency_count (int64), latency p50, p99,
  // max (double), num_channels, then per channel: channel (string), count (int64), rate_hz,
  // expected_hz (double), drops, late (int64).
  int64_t pos = kFingerprintBytes + 8 + 8;
  if (!skip_string(p, size, &pos)) return true;
  pos += 8 * 11;
  return count_fits(p, size, pos, kMinStringBytes + 5 * 8);
}

/// True if `msg` encodes back to exactly `size` bytes equal to `data`.
template <typename T>
bool encodes_back(const T& msg, const void* data, int size) {
  thread_local std::vector<uint8_t> buffer;
  if (msg.getEncodedSize() != size) return false;
  buffer.resize(static_cast<std::size_t>(size));
  return msg.encode(buffer.data(), 0, size) == size && std::memcmp(buffer.data(), data, buffer.size()) == 0;
}

}  // namespace detail

/// Decodes `size` bytes as one T. True only if the bytes are exactly one T (right fingerprint,
/// nothing short, nothing left over, array counts that fit the bytes, and bytes the encoder
/// writes back unchanged). On false, `error` (if given) says why.
template <typename T>
bool decode_exact(const void* data, int size, T& msg, std::string* error = nullptr) {
  try {
    if (size < 0 || !detail::array_counts_fit<T>(static_cast<const uint8_t*>(data), size)) {
      if (error) *error = "cannot decode as " + std::string(T::getTypeName()) + " (an array count larger than its " + std::to_string(size) + " bytes)";
      return false;
    }
    if (msg.decode(data, 0, size) == size) {
      if (detail::encodes_back(msg, data, size)) return true;
      if (error) {
        *error = "cannot decode as " + std::string(T::getTypeName()) + " (a string with a NUL inside or without its terminating NUL, " +
                 std::to_string(size) + " bytes)";
      }
      return false;
    }
    if (error) *error = "cannot decode as " + std::string(T::getTypeName()) + " (wrong type or truncated, " + std::to_string(size) + " bytes)";
  } catch (const std::exception& e) {
    if (error) *error = "decoding as " + std::string(T::getTypeName()) + " failed: " + e.what();
  }
  return false;
}

/// Largest forward step of a publisher's `seq` taken as genuine: a message further ahead, or
/// behind, does not continue the sequence and is not trusted (a stray publisher, or random bytes
/// that happened to decode). At the rig's highest rate this is 10 s of lost messages.
constexpr int64_t kMaxSeqStep = 10000;

/// True if `seq` may follow `last_seq` (-1: nothing yet) from the same publisher. The same
/// seq again is a repeat (the lockstep master resends a tick whose acknowledgement is missing).
inline bool seq_continues(int64_t last_seq, int64_t seq) {
  if (last_seq < 0) return seq >= 0 && seq < kMaxSeqStep;
  return seq >= last_seq && seq - last_seq <= kMaxSeqStep;  // equal: a repeat (a resent tick)
}

}  // namespace nimble::contract
