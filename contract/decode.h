#pragma once
/// Decoding a received LCM message without trusting it.
///
/// LCM 1.3.1's generated decoders check sizes but not everything. The rig's build adds the
/// string-length and array-count checks they lack (cmake/LcmDecodeChecks.cmake: a zero or
/// negative string length, an array count larger than the message). One thing is left to this
/// header: a string is taken with whatever its terminating byte holds and with NUL bytes
/// inside, which the encoder (strlen) cannot write back; the message decodes, but a node that
/// copies such a string into a message of its own (the run id into RIG_CLOCK) can no longer
/// publish it. Every reader of messages from the bus or a log decodes through decode_exact(),
/// so that such bytes are one more malformed message, never an exception that ends a process,
/// an allocation out of proportion to the message, or a message that cannot be sent on.

#include <cstdint>
#include <cstring>
#include <exception>
#include <string>
#include <vector>

namespace nimble::contract {

namespace detail {

/// True if `msg` encodes back to exactly `size` bytes equal to `data`.
template <typename T>
bool encodes_back(const T& msg, const void* data, int size) {
  thread_local std::vector<uint8_t> buffer;
  if (msg.getEncodedSize() != size) return false;
  buffer.resize(static_cast<std::size_t>(size));
  return msg.encode(buffer.data(), 0, size) == size && std::memcmp(buffer.data(), data, buffer.size()) == 0;
}

/// Decodes `size` bytes as one T; decode_exact() and decode_as() below. With `encodes_back_check`
/// false the bytes are not encoded again to compare.
template <typename T>
bool decode_bytes(const void* data, int size, T& msg, std::string* error, bool encodes_back_check) {
  try {
    if (msg.decode(data, 0, size) == size) {
      if (!encodes_back_check || encodes_back(msg, data, size)) return true;
      if (error) {
        *error = "cannot decode as " + std::string(T::getTypeName()) +
                 " (a string with a NUL inside or without its terminating NUL, " + std::to_string(size) + " bytes)";
      }
      return false;
    }
    if (error)
      *error = "cannot decode as " + std::string(T::getTypeName()) + " (wrong type or truncated, " +
               std::to_string(size) + " bytes)";
  } catch (const std::exception& e) {
    if (error) *error = "decoding as " + std::string(T::getTypeName()) + " failed: " + e.what();
  }
  return false;
}

}  // namespace detail

/// Decodes `size` bytes as one T. True only if the bytes are exactly one T (right fingerprint,
/// nothing short, nothing left over, and bytes the encoder writes back unchanged). On false, `error` (if given) says why.
template <typename T>
bool decode_exact(const void* data, int size, T& msg, std::string* error = nullptr) {
  return detail::decode_bytes(data, size, msg, error, true);
}

/// decode_exact(), except for bytes the rig's own encoder wrote for a T in this process
/// (`own_encoding`: an in-process run's messages, InprocessHub::delivering_own_encoding()), which
/// are not encoded again to compare: encoding is a function of the message, so the message they
/// decode to encodes back to them by construction. Every other check is made.
template <typename T>
bool decode_as(const void* data, int size, T& msg, bool own_encoding, std::string* error = nullptr) {
  return detail::decode_bytes(data, size, msg, error, !own_encoding);
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
