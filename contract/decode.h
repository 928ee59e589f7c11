#pragma once
/// Decoding a received LCM message without trusting it.
///
/// LCM 1.3.1's generated decoders check sizes but not everything: a string field whose encoded
/// length is 0 makes them call std::string::assign(p, -1), which throws. Every reader of
/// messages from the bus or a log decodes through decode_exact(), so that such bytes are one
/// more malformed message, never an exception that ends a process.

#include <cstdint>
#include <exception>
#include <string>

namespace nimble::contract {

/// Decodes `size` bytes as one T. True only if the bytes are exactly one T (right fingerprint,
/// nothing short, nothing left over). On false, `error` (if given) says why.
template <typename T>
bool decode_exact(const void* data, int size, T& msg, std::string* error = nullptr) {
  try {
    if (msg.decode(data, 0, size) == size) return true;
    if (error) {
      *error = "cannot decode as " + std::string(T::getTypeName()) + " (wrong type or truncated, " +
               std::to_string(size) + " bytes)";
    }
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
