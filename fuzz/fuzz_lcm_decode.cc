// Fuzz target: the decoders of every LCM type of lcmtypes/, as every reader of the bus or a log
// uses them (contract::decode_exact). Each input is offered to all 15 types. Bytes that do not
// decode exactly must be refused without an exception escaping; bytes that do must re-encode to
// the same size and encode stably (encode(decode(encode(m))) == encode(m)).

#include <cstddef>
#include <cstdint>

#include "fuzz/fuzz_support.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size > (1u << 20)) return 0;  // LCM messages are far smaller; keeps sizes in int
  for (const auto& type : nimble::fuzz::lcm_types()) type.check_round_trip(data, static_cast<int>(size));
  return 0;
}
