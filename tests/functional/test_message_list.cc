// Functional test of the one list of message types (nimble/rig_message_list.hpp, generated from
// lcmtypes/*.lcm at build time): every place that needs every type or every field takes it from
// there, and what a new message still needs by hand (its channel, its rate) is checked here, so
// that adding a message (docs/contract.md, "Adding a stream message") fails where a step is
// missed.

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <map>
#include <string>
#include <type_traits>
#include <vector>

#include <catch2/catch.hpp>

#include <nimble/rig_message_list.hpp>

#include "contract/channels.h"
#include "contract/rates.h"
#include "fuzz/fuzz_support.h"
#include "lcmjson/lcm_json.h"
#include "../support/lcm_samples.h"

using namespace nimble;

namespace {

/// The types of the generated list, in its order.
std::vector<std::string> listed_types() {
  std::vector<std::string> names;
  for_each_message_type([&names](auto type) { names.push_back(decltype(type)::type::getTypeName()); });
  return names;
}

/// Fails for a field of `filled` that still holds the value of a default message (a field the
/// samples do not fill).
struct RequireChanged {
  template <typename T>
  void operator()(const char* name, const T& filled, const T& empty) const {
    INFO(name);
    CHECK_FALSE(filled == empty);
  }
  template <typename T, std::size_t N>
  void operator()(const char* name, const T (&filled)[N], const T (&empty)[N]) const {
    for (std::size_t i = 0; i < N; ++i)
      (*this)((std::string(name) + "[" + std::to_string(i) + "]").c_str(), filled[i], empty[i]);
  }
};

}  // namespace

TEST_CASE("every .lcm file of lcmtypes/ is a type of the list, of the viewers and of the fuzz targets",
          "[message_list]") {
  std::vector<std::string> files;
  for (const auto& entry : std::filesystem::directory_iterator(std::string(RIG_SOURCE_DIR) + "/lcmtypes")) {
    if (entry.path().extension() == ".lcm") files.push_back(entry.path().stem().string());
  }
  std::sort(files.begin(), files.end());
  REQUIRE(files.size() >= 15);
  CHECK(listed_types() == files);
  CHECK(static_cast<std::size_t>(kRigMessageCount) == files.size());

  std::vector<std::string> viewers;  // lcmjson: the .lcm texts built into the library
  for (const auto& t : lcmjson::rig_types()) viewers.push_back(t.name);
  CHECK(viewers == files);

  std::vector<std::string> fuzzed;  // fuzz/fuzz_support.cc: the types fuzz_lcm_decode and the node targets decode
  for (const auto& t : fuzz::lcm_types()) fuzzed.push_back(t.name);
  CHECK(fuzzed == files);
}

TEST_CASE("the list's fields are those of each .lcm file, in order", "[message_list]") {
  for_each_message_type([](auto type) {
    using M = typename decltype(type)::type;
    INFO(M::getTypeName());
    const lcmjson::LcmStruct* parsed = lcmjson::find_rig_type(M::getTypeName());
    REQUIRE(parsed != nullptr);
    CHECK(parsed->fingerprint == static_cast<uint64_t>(M::getHash()));
    REQUIRE(parsed->fields.size() == static_cast<std::size_t>(MessageFields<M>::field_count));
    std::vector<std::string> visited;
    M m{};
    for_each_field(m, [&visited](const char* name, auto&) { visited.push_back(name); });
    for (std::size_t i = 0; i < parsed->fields.size(); ++i) {
      const lcmjson::LcmField& f = parsed->fields[i];
      const MessageFieldInfo& info = MessageFields<M>::fields()[i];
      INFO(f.name);
      CHECK(info.name == f.name);
      CHECK(visited.at(i) == f.name);
      CHECK(info.type == f.type);
      CHECK(std::string(info.size) == (f.dims.empty() ? "" : f.dims[0]));
    }
  });
}

TEST_CASE("every channel carries a type of the list, and every type has a channel or is declared without one",
          "[message_list]") {
  const std::vector<std::string> types = listed_types();
  for (const contract::ChannelSpec& c : contract::channel_table()) {
    INFO(c.name << " carries " << c.type);
    CHECK(std::find(types.begin(), types.end(), c.type) != types.end());
  }
  const std::vector<std::string>& without = contract::types_without_channel();
  for (const std::string& type : types) {
    INFO(type << ": no row in contract/channels.cc, and not in contract::types_without_channel()");
    const bool on_channel = std::any_of(contract::channel_table().begin(), contract::channel_table().end(),
                                        [&](const contract::ChannelSpec& c) { return c.type == type; });
    const bool declared = std::find(without.begin(), without.end(), type) != without.end();
    CHECK(on_channel != declared);
  }
}

TEST_CASE("every channel published at a rate has its nominal rate (contract/rates.cc)", "[message_list]") {
  // A run with every process and link: each channel but those published on an event ("on start
  // and stop", "on event") has a nominal rate.
  contract::ProcessRates r;
  r.plant_hz = 1000.0;
  r.truth_hz = 1000.0;
  r.feedback_hz = 100.0;
  r.imu_hz = 512.0;
  r.controller_hz = 512.0;
  r.estimator_hz = 512.0;
  r.mocap_hz = 200.0;
  r.can_link = true;
  r.can_health_hz = 2.0;
  const std::map<std::string, double> hz = contract::expected_rates(r, contract::RunShape{true, 10.0, 6});
  for (const contract::ChannelSpec& c : contract::channel_table()) {
    INFO(c.name << " (" << c.rate << ")");
    const bool on_event = c.rate.rfind("on ", 0) == 0;
    CHECK(hz.count(c.name) == (on_event ? 0u : 1u));
  }
}

TEST_CASE("the samples fill every field of every type, and a message equals itself through its bytes",
          "[message_list]") {
  for_each_message_type([](auto type) {
    using M = typename decltype(type)::type;
    INFO(M::getTypeName());
    M filled{};
    rig_test::Distinct g;
    rig_test::fill(filled, g);
    const M empty{};
    bind_fields(filled, empty, RequireChanged{});
    std::vector<uint8_t> bytes(static_cast<std::size_t>(filled.getEncodedSize()));
    REQUIRE(filled.encode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
    M decoded{};
    REQUIRE(decoded.decode(bytes.data(), 0, static_cast<int>(bytes.size())) == static_cast<int>(bytes.size()));
    rig_test::require_equal(filled, decoded);
  });
}
