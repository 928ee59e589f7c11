// Fuzz target: the decoders of every LCM type of lcmtypes/, as every reader of the bus or a log
// uses them (contract::decode_exact), and the viewers' JSON view of the same bytes
// (lcmjson::to_json). Each input is offered to all 15 types. Bytes that do not decode exactly
// must be refused without an exception escaping; bytes that do must re-encode to the same size
// and encode stably (encode(decode(encode(m))) == encode(m)). The JSON view takes exactly the
// bytes the generated decoder takes, and what it writes is valid JSON.

#include <cstddef>
#include <cstdint>

#include <nlohmann/json.hpp>

#include "fuzz/fuzz_support.h"
#include "lcmjson/lcm_json.h"

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  if (size > (1u << 20)) return 0;  // LCM messages are far smaller; keeps sizes in int
  nimble::lcmjson::JsonMessage message;
  for (const auto& type : nimble::fuzz::lcm_types()) {
    type.check_round_trip(data, static_cast<int>(size));
    const nimble::lcmjson::LcmStruct* parsed = nimble::lcmjson::find_rig_type(type.name);
    nimble::fuzz::require(parsed != nullptr, type.name + ": not among lcmjson's types");
    const std::string why = nimble::lcmjson::to_json(*parsed, data, size, &message);
    const bool exact = type.decodes(data, static_cast<int>(size));
    nimble::fuzz::require(exact == why.empty(), type.name + ": the generated decoder " + (exact ? "takes" : "refuses") +
                                                    " the bytes, the JSON view " +
                                                    (why.empty() ? "takes them" : "says " + why));
    if (why.empty()) {
      nimble::fuzz::require(nlohmann::json::accept(message.json), type.name + ": invalid JSON " + message.json);
    }
  }
  return 0;
}
