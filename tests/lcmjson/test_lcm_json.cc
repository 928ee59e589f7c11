// The rig's LCM types parsed from their .lcm files, messages as JSON, types as JSON Schema:
// checked against the C++ code lcm-gen generated from the same files.

#include <cmath>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <nimble/rig_message_list.hpp>

#include "contract/channels.h"
#include "contract/decode.h"
#include "lcmjson/lcm_json.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kImu;

using nimble::lcmjson::LcmStruct;
using nlohmann::json;

namespace {

/// Encodes `value` (a JSON message) as `type` would be encoded by LCM: the test's own encoder,
/// independent of lcm_json.cc's decoder.
void put_be(std::vector<uint8_t>* out, uint64_t v, int n) {
  for (int i = n - 1; i >= 0; --i) out->push_back(static_cast<uint8_t>(v >> (8 * i)));
}

void encode_value(const std::string& type, const json& v, std::vector<uint8_t>* out) {
  if (type == "int8_t" || type == "byte") {
    put_be(out, static_cast<uint64_t>(v.get<int64_t>()), 1);
  } else if (type == "boolean") {
    put_be(out, v.get<bool>() ? 1 : 0, 1);
  } else if (type == "int16_t") {
    put_be(out, static_cast<uint64_t>(v.get<int64_t>()), 2);
  } else if (type == "int32_t") {
    put_be(out, static_cast<uint64_t>(v.get<int64_t>()), 4);
  } else if (type == "int64_t") {
    put_be(out, static_cast<uint64_t>(v.get<int64_t>()), 8);
  } else if (type == "float") {
    const float f = v.is_null() ? NAN : v.get<float>();
    uint32_t bits;
    std::memcpy(&bits, &f, sizeof bits);
    put_be(out, bits, 4);
  } else if (type == "double") {
    const double d = v.is_null() ? NAN : v.get<double>();
    uint64_t bits;
    std::memcpy(&bits, &d, sizeof bits);
    put_be(out, bits, 8);
  } else {
    const std::string s = v.get<std::string>();
    put_be(out, s.size() + 1, 4);
    out->insert(out->end(), s.begin(), s.end());
    out->push_back(0);
  }
}

std::vector<uint8_t> encode_json(const LcmStruct& type, const json& message) {
  std::vector<uint8_t> out;
  put_be(&out, type.fingerprint, 8);
  for (const auto& f : type.fields) {
    if (f.dims.empty()) {
      encode_value(f.type, message.at(f.name), &out);
    } else {
      for (const auto& e : message.at(f.name)) encode_value(f.type, e, &out);
    }
  }
  return out;
}

/// A random message of `type` as bytes (random values of every field, variable arrays of 0-4).
std::vector<uint8_t> random_message(const LcmStruct& type, std::mt19937_64& rng) {
  std::vector<uint8_t> out;
  put_be(&out, type.fingerprint, 8);
  std::vector<int64_t> scalar(type.fields.size(), 0);
  std::uniform_real_distribution<double> real(-1e6, 1e6);
  for (std::size_t i = 0; i < type.fields.size(); ++i) {
    const auto& f = type.fields[i];
    std::size_t count = 1;
    for (const auto& d : f.dims) {
      if (d[0] >= '0' && d[0] <= '9') {
        count *= std::stoul(d);
      } else {
        for (std::size_t k = 0; k < i; ++k) {
          if (type.fields[k].name == d) count *= static_cast<std::size_t>(scalar[k]);
        }
      }
    }
    for (std::size_t n = 0; n < count; ++n) {
      if (f.type == "double" || f.type == "float") {
        encode_value(f.type, json(f.type == "float" ? static_cast<double>(static_cast<float>(real(rng))) : real(rng)),
                     &out);
      } else if (f.type == "boolean") {
        encode_value(f.type, json(rng() % 2 == 1), &out);
      } else if (f.type == "string") {
        const char* words[] = {"plant", "", "roll \"step\"\\", "caf\xc3\xa9", "tab\tnewline\n"};
        encode_value(f.type, json(std::string(words[rng() % 5])), &out);
      } else {
        // Integers that may size an array stay small; others span their type.
        int64_t v = static_cast<int64_t>(rng() % 5);
        if (f.name.rfind("num_", 0) != 0) {
          const int bits = f.type == "int8_t"    ? 7
                           : f.type == "int16_t" ? 15
                           : f.type == "int32_t" ? 31
                           : f.type == "byte"    ? 8
                                                 : 62;
          v = static_cast<int64_t>(rng() % (uint64_t{1} << bits));
          if (f.type != "byte" && rng() % 2) v = -v;
        }
        scalar[i] = v;
        encode_value(f.type, json(v), &out);
      }
    }
  }
  return out;
}

template <typename T>
void check_against_generated(std::mt19937_64& rng) {
  const LcmStruct* type = nimble::lcmjson::find_rig_type(T::getTypeName());
  INFO(T::getTypeName());
  REQUIRE(type != nullptr);
  // lcm-gen's fingerprint, computed from the parse.
  CHECK(type->fingerprint == static_cast<uint64_t>(T::getHash()));
  for (int trial = 0; trial < 50; ++trial) {
    const std::vector<uint8_t> bytes = random_message(*type, rng);
    // The generated decoder takes the bytes as exactly one T: the parse has the layout right.
    T decoded;
    std::string why;
    REQUIRE(nimble::contract::decode_exact(bytes.data(), static_cast<int>(bytes.size()), decoded, &why));
    nimble::lcmjson::JsonMessage m;
    REQUIRE(nimble::lcmjson::to_json(*type, bytes.data(), bytes.size(), &m) == "");
    const json j = json::parse(m.json);
    // Every field, in order, and the same bytes when encoded back from the JSON.
    REQUIRE(j.size() == type->fields.size());
    CHECK(encode_json(*type, j) == bytes);
    CHECK(m.rig_time_us == nimble::lcmjson::rig_time_us(*type, bytes.data(), bytes.size()));
  }
}

}  // namespace

TEST_CASE(
    "lcmjson: every rig type parsed from its .lcm file has lcm-gen's fingerprint, and its JSON encodes back to the "
    "same bytes",
    "[lcmjson]") {
  std::mt19937_64 rng(7);
  CHECK(nimble::lcmjson::rig_types().size() == static_cast<std::size_t>(nimble::kRigMessageCount));
  nimble::for_each_message_type([&rng](auto type) { check_against_generated<typename decltype(type)::type>(rng); });
}

TEST_CASE("lcmjson: a truth message's JSON holds its values, NaN as null, and its rig time", "[lcmjson]") {
  nimble::truth_state_t t{};
  t.utime = 1234567;
  t.seq = 3;
  t.step = -1;
  t.euler_rad[0] = 0.125;
  t.euler_rad[1] = -1e-300;
  t.euler_rad[2] = NAN;
  t.omega_body_radps[0] = 0.1;
  t.throttle_pct = INFINITY;
  std::vector<uint8_t> bytes(static_cast<std::size_t>(t.getEncodedSize()));
  t.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  const LcmStruct* type = nimble::lcmjson::rig_type_for_channel(nimble::contract::channels::kTruth);
  REQUIRE(type != nullptr);
  nimble::lcmjson::JsonMessage m;
  REQUIRE(nimble::lcmjson::to_json(*type, bytes.data(), bytes.size(), &m) == "");
  const json j = json::parse(m.json);
  CHECK(j["utime"] == 1234567);
  CHECK(j["euler_rad"][0].get<double>() == 0.125);
  CHECK(j["euler_rad"][1].get<double>() == -1e-300);
  CHECK(j["euler_rad"][2].is_null());
  CHECK(j["omega_body_radps"][0].get<double>() == 0.1);
  CHECK(j["throttle_pct"].is_null());
  CHECK(m.rig_time_us == 1234567);
  CHECK(nimble::lcmjson::rig_time_us(*type, bytes.data(), bytes.size()) == 1234567);

  // A time no run reaches (garbage that kept the fingerprint) is no rig time: the viewers do not
  // carry it on to the messages without one.
  t.utime = 9166731080479000000;
  t.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  REQUIRE(nimble::lcmjson::to_json(*type, bytes.data(), bytes.size(), &m) == "");
  CHECK(json::parse(m.json)["utime"] == 9166731080479000000);
  CHECK(m.rig_time_us == -1);
  CHECK(nimble::lcmjson::rig_time_us(*type, bytes.data(), bytes.size()) == -1);
}

TEST_CASE("lcmjson: rig time is utime where it is rig time, rig_utime for a fault, none for the wall-clock channels",
          "[lcmjson]") {
  using nimble::lcmjson::find_rig_type;
  auto field = [](const char* type) {
    const LcmStruct* t = find_rig_type(type);
    return t->rig_time_field < 0 ? std::string() : t->fields[static_cast<std::size_t>(t->rig_time_field)].name;
  };
  for (const char* t :
       {"truth_state_t", "imu_sample_t", "mocap_pose_t", "estimator_state_t", "actuator_command_t",
        "actuator_feedback_t", "attitude_setpoint_t", "controller_status_t", "rig_clock_t", "step_ack_t"}) {
    INFO(t);
    CHECK(field(t) == "utime");
  }
  CHECK(field("fault_event_t") == "rig_utime");
  for (const char* t : {"heartbeat_t", "timing_health_t", "can_health_t", "run_control_t"}) {
    INFO(t);
    CHECK(field(t).empty());
  }
  // Every channel of the contract has its type.
  for (const auto& spec : nimble::contract::channel_table()) {
    INFO(spec.name);
    CHECK(nimble::lcmjson::rig_type_for_channel(spec.name) != nullptr);
  }
  CHECK(nimble::lcmjson::rig_type_for_channel("NOT_A_CHANNEL") == nullptr);
}

TEST_CASE("lcmjson: bytes that are not exactly one message are refused with the reason, at every truncation",
          "[lcmjson]") {
  // fuzz/fuzz_lcm_decode checks on arbitrary bytes that the JSON view takes exactly what the
  // generated decoder (contract::decode_exact) takes.
  const LcmStruct* type = nimble::lcmjson::find_rig_type("nimble.fault_event_t");
  REQUIRE(type != nullptr);
  nimble::fault_event_t f{};
  f.process = "estimator";
  f.channel = kImu;
  f.message = "stale";
  std::vector<uint8_t> bytes(static_cast<std::size_t>(f.getEncodedSize()));
  f.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  nimble::lcmjson::JsonMessage m;
  REQUIRE(nimble::lcmjson::to_json(*type, bytes.data(), bytes.size(), &m).empty());
  for (std::size_t n = 0; n < bytes.size(); ++n) {
    INFO(n);
    CHECK_FALSE(nimble::lcmjson::to_json(*type, bytes.data(), n, &m).empty());
  }
  std::vector<uint8_t> longer = bytes;
  longer.push_back(0);
  CHECK(nimble::lcmjson::to_json(*type, longer.data(), longer.size(), &m).find("left over") != std::string::npos);
  std::vector<uint8_t> other = bytes;
  other[3] ^= 1;
  CHECK(nimble::lcmjson::to_json(*type, other.data(), other.size(), &m).find("fingerprint") != std::string::npos);
  CHECK(nimble::lcmjson::rig_time_us(*type, other.data(), other.size()) == -1);
  // The terminating NUL of the last string, made a letter.
  std::vector<uint8_t> unterminated = bytes;
  unterminated.back() = 'x';
  CHECK(nimble::lcmjson::to_json(*type, unterminated.data(), unterminated.size(), &m).find("NUL") != std::string::npos);

  // A boolean byte other than 0 or 1 is true, as LCM's decoder takes it; a negative array count
  // is refused.
  const LcmStruct* status = nimble::lcmjson::find_rig_type("controller_status_t");
  nimble::controller_status_t s{};
  s.gain_set = "fast";
  std::vector<uint8_t> sb(static_cast<std::size_t>(s.getEncodedSize()));
  s.encode(sb.data(), 0, static_cast<int>(sb.size()));
  sb[sb.size() - 1 - 8 - 1 - 1] = 2;  // `saturated`, before input_source, input_age_us and failsafe
  REQUIRE(nimble::lcmjson::to_json(*status, sb.data(), sb.size(), &m).empty());
  CHECK(json::parse(m.json)["saturated"] == true);
  const LcmStruct* control = nimble::lcmjson::find_rig_type("run_control_t");
  nimble::run_control_t rc{};
  rc.run_id = "r";
  rc.num_participants = 0;
  std::vector<uint8_t> rb(static_cast<std::size_t>(rc.getEncodedSize()));
  rc.encode(rb.data(), 0, static_cast<int>(rb.size()));
  rb[rb.size() - 4] = 0xff;  // num_participants, the last field, made negative
  CHECK(nimble::lcmjson::to_json(*control, rb.data(), rb.size(), &m).find("array size") != std::string::npos);
}

TEST_CASE("lcmjson: a string that is not UTF-8 stays valid JSON and keeps its bytes", "[lcmjson]") {
  const LcmStruct* type = nimble::lcmjson::find_rig_type("heartbeat_t");
  nimble::heartbeat_t h{};
  h.process = std::string("a\xff\xc3\xa9\x01z");
  h.config_digest = "d";
  std::vector<uint8_t> bytes(static_cast<std::size_t>(h.getEncodedSize()));
  h.encode(bytes.data(), 0, static_cast<int>(bytes.size()));
  nimble::lcmjson::JsonMessage m;
  REQUIRE(nimble::lcmjson::to_json(*type, bytes.data(), bytes.size(), &m).empty());
  const json j = json::parse(m.json);                                  // throws on invalid UTF-8
  CHECK(j["process"].get<std::string>() == "a\xc3\xbf\xc3\xa9\x01z");  // 0xff as U+00FF, the rest as it was
}

TEST_CASE("lcmjson: each type's JSON Schema has every field with its type, size, description and unit", "[lcmjson]") {
  const LcmStruct* type = nimble::lcmjson::find_rig_type("truth_state_t");
  const json s = json::parse(nimble::lcmjson::json_schema(*type));
  CHECK(s["title"] == "nimble.truth_state_t");
  CHECK(s["type"] == "object");
  CHECK(s["required"].size() == type->fields.size());
  CHECK(s["properties"]["utime"]["type"] == "integer");
  CHECK(s["properties"]["euler_rad"]["type"] == "array");
  CHECK(s["properties"]["euler_rad"]["minItems"] == 3);
  CHECK(s["properties"]["euler_rad"]["maxItems"] == 3);
  CHECK(s["properties"]["euler_rad"]["items"]["type"] == json::array({"number", "null"}));
  CHECK(s["properties"]["euler_rad"]["x-unit"] == "rad");
  CHECK(s["properties"]["omega_body_radps"]["x-unit"] == "rad/s");
  CHECK(s["properties"]["delta_f_radps"]["description"].get<std::string>().find("flap_freq_left_radps") !=
        std::string::npos);
  const json f = json::parse(nimble::lcmjson::json_schema(*nimble::lcmjson::find_rig_type("fault_event_t")));
  CHECK(f["x-constants"]["CODE_FAILSAFE"]["value"] == 18);
  CHECK(f["properties"]["severity"]["minimum"] == -128);
  const json t = json::parse(nimble::lcmjson::json_schema(*nimble::lcmjson::find_rig_type("timing_health_t")));
  CHECK(t["properties"]["channel"]["type"] == "array");
  CHECK_FALSE(t["properties"]["channel"].contains("minItems"));
  CHECK(t["properties"]["channel"]["description"].get<std::string>().find("num_channels") != std::string::npos);
}

TEST_CASE("lcmjson: a .lcm text the parser does not understand is an error naming file and line", "[lcmjson]") {
  using nimble::lcmjson::parse_lcm;
  auto error = [](const std::string& text) {
    try {
      parse_lcm(text, "x.lcm");
    } catch (const std::runtime_error& e) {
      return std::string(e.what());
    }
    return std::string();
  };
  CHECK(error("package p;\nstruct s {\n  int64_t a\n}\n").find("x.lcm:4") != std::string::npos);
  CHECK(error("struct s { other_t a; }").find("not a primitive") != std::string::npos);
  CHECK(error("struct s { double a[n]; }").find("not an earlier integer field") != std::string::npos);
  CHECK(error("struct s { double a; double a; }").find("twice") != std::string::npos);
  CHECK(error("struct s { /* open").find("does not end") != std::string::npos);
  CHECK(error("message s { }").find("expected 'package' or 'struct'") != std::string::npos);
  const auto parsed = parse_lcm(
      "package p;\n/// A thing.\nstruct s {\n  /// Size [-].\n  int32_t n;\n  /// Values [m].\n  double v[n][2];\n  "
      "const int8_t A = 1, B = -2;\n}\n",
      "y.lcm");
  REQUIRE(parsed.size() == 1);
  CHECK(parsed[0].full_name() == "p.s");
  CHECK(parsed[0].comment == "A thing.");
  CHECK(parsed[0].fields[1].dims == std::vector<std::string>{"n", "2"});
  CHECK(parsed[0].fields[1].unit == "m");
  CHECK(parsed[0].consts.size() == 2);
  CHECK(parsed[0].consts[1].value == "-2");
}
