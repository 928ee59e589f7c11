#pragma once
/// The rig's LCM messages as JSON, and their types as JSON Schema, for the viewers that do not
/// read LCM (MCAP files for Foxglove, Lichtblick and PlotJuggler; the live Foxglove WebSocket
/// view).
///
/// The types come from the .lcm files themselves (lcmtypes/, embedded in the library at build
/// time), parsed here: field names, primitive types, fixed and variable array sizes, constants,
/// and the `///` comment above each field, whose trailing `[unit]` becomes the field's unit. The
/// fingerprint is computed from that parse as lcm-gen computes it, and a test checks it against
/// the generated C++ types, so a .lcm change that the parse would misread fails the build's tests.
///
/// A message is decoded by walking its bytes (big-endian, as LCM encodes) against its type: no
/// generated code is involved, and bytes that are not exactly one message of the type (wrong
/// fingerprint, short, bytes left over, a string without its NUL) are refused with the reason.
/// Arrays are written flat (one JSON array per field; the rig has no nested types).
/// Doubles that JSON cannot hold (NaN, +-Inf) are written as null, and the schema allows it.

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace nimble::lcmjson {

/// One field of an LCM struct.
struct LcmField {
  std::string name;
  std::string type;               ///< int8_t, int16_t, int32_t, int64_t, byte, boolean, float, double, string
  std::vector<std::string> dims;  ///< per dimension: a number (fixed) or the name of an earlier integer field
  std::string comment;            ///< the `///` comment above the field, lines joined by a space
  std::string unit;               ///< the comment's last "[...]" (e.g. "rad/s"), "" if none
};

/// One `const` of an LCM struct.
struct LcmConst {
  std::string name;
  std::string type;
  std::string value;  ///< as written
  std::string comment;
};

/// One LCM struct as its .lcm file declares it.
struct LcmStruct {
  std::string package;  ///< e.g. "nimble"
  std::string name;     ///< e.g. "truth_state_t"
  std::string comment;  ///< the `///` comment above the struct
  std::vector<LcmField> fields;
  std::vector<LcmConst> consts;
  /// The 8-byte fingerprint an encoded message starts with (lcm-gen's hash, rotated left by one).
  uint64_t fingerprint = 0;
  /// Index in `fields` of the int64 field holding the message's rig (simulated) time [us]:
  /// `utime` unless its comment says it is the wall clock, else `rig_utime`; -1 if none.
  int rig_time_field = -1;
  /// The text of the .lcm file that declares it (the schema of its raw LCM bytes).
  std::string source;
  /// The .lcm file's name, e.g. "truth_state_t.lcm".
  std::string file;

  std::string full_name() const { return package.empty() ? name : package + "." + name; }
};

/// Parses the text of one .lcm file (`file` names it in errors).
/// @throws std::runtime_error naming the file and line of anything it does not understand.
std::vector<LcmStruct> parse_lcm(const std::string& text, const std::string& file);

/// The rig's types (lcmtypes/*.lcm as built into the library), parsed once.
const std::vector<LcmStruct>& rig_types();
/// The rig's type called `name` ("truth_state_t" or "nimble.truth_state_t"), or nullptr.
const LcmStruct* find_rig_type(const std::string& name);
/// The type the rig's contract (contract/channels.h) gives `channel`, or nullptr for a channel
/// the contract does not know.
const LcmStruct* rig_type_for_channel(const std::string& channel);

/// Bytes a message of `type` typically encodes to: its fingerprint and fields, each string at
/// kTypicalStringBytes of text and each variable-length array at kTypicalArrayLength elements
/// (what the rig's messages hold: process, channel and manoeuvre names; a handful of channels).
/// For sizing logs before a run, not for decoding.
int typical_encoded_size(const LcmStruct& type);
inline constexpr int kTypicalStringBytes = 16;
inline constexpr int kTypicalArrayLength = 6;

/// The JSON Schema (draft-07, which Foxglove's and Ajv's readers take) of `type`'s JSON messages: an object with every field
/// required, integers as "integer" with their range, doubles as "number" or null, booleans,
/// strings, arrays with their fixed size; each field's comment as "description" and its unit as
/// "x-unit"; the constants in "x-constants"; the title is the type's full name.
std::string json_schema(const LcmStruct& type);

/// A decoded message: its JSON text and its rig time.
struct JsonMessage {
  std::string json;
  /// The rig_time_field's value; -1 if the type has none, or the value cannot be a rig time
  /// (outside 0..transport::kMaxSimUtime: a garbage message that kept its fingerprint).
  int64_t rig_time_us = -1;
};

/// Decodes `size` bytes of one encoded LCM message of `type` into `out` (JSON appended to
/// `out->json` after clearing it, so a reused JsonMessage reuses its buffer).
/// @return "" on success, else why the bytes are not one message of `type`.
std::string to_json(const LcmStruct& type, const void* data, std::size_t size, JsonMessage* out);

/// The message's rig time [us] without decoding the rest (-1 if the type has none, the bytes
/// are too short to hold it, or the value cannot be a rig time, as JsonMessage::rig_time_us).
int64_t rig_time_us(const LcmStruct& type, const void* data, std::size_t size);

}  // namespace nimble::lcmjson
