// Functional test of the message contract's owner (contract/): the channel table names every
// channel once with its real LCM type, lcmtypes/README.md shows the same table, and the nominal
// rates follow the configured ones.
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/rig_message_list.hpp>

#include "contract/channels.h"
#include "contract/faults.h"
#include "contract/rates.h"

using namespace nimble;
using namespace nimble::contract;
using namespace nimble::contract::channels;

namespace {

/// Every type of lcmtypes/ (the generated list).
std::set<std::string> type_names() {
  std::set<std::string> names;
  for_each_message_type([&names](auto type) { names.insert(decltype(type)::type::getTypeName()); });
  return names;
}

/// The values of the channel name constants of contract/channels.h (`inline const std::string
/// kName = "NAME";`), read from the header as tests/meta/check_house_rules.py reads them.
std::set<std::string> channel_constants() {
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/contract/channels.h");
  REQUIRE(in.good());
  const std::regex constant(R"re(inline const std::string k\w+ = "([A-Z_]+)";)re");
  std::set<std::string> names;
  for (std::string line; std::getline(in, line);) {
    std::smatch m;
    if (std::regex_search(line, m, constant)) names.insert(m[1]);
  }
  return names;
}

/// The rows of the table under `## Channels` in lcmtypes/README.md (without header and rule).
std::vector<std::string> readme_channel_rows() {
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/lcmtypes/README.md");
  REQUIRE(in.good());
  std::vector<std::string> rows;
  bool in_section = false;
  int table_lines = 0;
  for (std::string line; std::getline(in, line);) {
    if (line.rfind("## ", 0) == 0) {
      in_section = line == "## Channels";
      continue;
    }
    if (!in_section) continue;
    if (line.rfind("|", 0) != 0) {
      if (table_lines > 0) break;  // the end of the table
      continue;
    }
    if (++table_lines > 2) rows.push_back(line);  // past the header row and the |---| rule
  }
  return rows;
}

}  // namespace

TEST_CASE("the channel table names every channel once, with a generated LCM type", "[contract]") {
  const std::set<std::string> types = type_names();
  const std::set<std::string> constants = channel_constants();
  REQUIRE(constants.size() >= 17);
  std::set<std::string> names;
  for (const ChannelSpec& c : channel_table()) {
    INFO(c.name);
    CHECK(names.insert(c.name).second);
    CHECK(constants.count(c.name) == 1);
    CHECK(types.count(c.type) == 1);
    CHECK_FALSE(c.publishers.empty());
    CHECK_FALSE(c.rate.empty());
    REQUIRE(find_channel(c.name) == &c);
  }
  CHECK(names == constants);
  CHECK(find_channel("NO_SUCH_CHANNEL") == nullptr);
  CHECK(find_channel(kTruth)->type == truth_state_t::getTypeName());
  CHECK(find_channel(kFault)->type == fault_event_t::getTypeName());
}

TEST_CASE("lcmtypes/README.md shows the contract's channel table", "[contract]") {
  // On a difference, the expected table is printed: paste it into lcmtypes/README.md.
  std::ostringstream expected;
  for (const ChannelSpec& c : channel_table()) expected << markdown_row(c) << "\n";
  INFO("expected rows of the channel table in lcmtypes/README.md:\n" << expected.str());
  const std::vector<std::string> rows = readme_channel_rows();
  REQUIRE(rows.size() == channel_table().size());
  for (std::size_t i = 0; i < rows.size(); ++i) CHECK(rows[i] == markdown_row(channel_table()[i]));
}

TEST_CASE("C++ code spells channel names only in contract/channels.h", "[contract]") {
  // Anything else names a channel through contract::channels. This file, which pins the names
  // on the wire, is the one exception.
  namespace fs = std::filesystem;
  const fs::path root(RIG_SOURCE_DIR);
  std::vector<std::string> literals;
  for (const ChannelSpec& c : channel_table()) literals.push_back('"' + c.name + '"');
  std::vector<std::string> found;
  for (auto it = fs::recursive_directory_iterator(root); it != fs::recursive_directory_iterator(); ++it) {
    const fs::path rel = fs::relative(it->path(), root);
    const std::string top = rel.begin()->string();
    if (it->is_directory() && it.depth() == 0 && (top == "contract" || top.rfind("build", 0) == 0 || top[0] == '.')) {
      it.disable_recursion_pending();
      continue;
    }
    const std::string ext = it->path().extension().string();
    if (!it->is_regular_file() || (ext != ".cc" && ext != ".h") || rel == "tests/functional/test_contract.cc") continue;
    std::ifstream in(it->path());
    int number = 0;
    for (std::string line; std::getline(in, line);) {
      ++number;
      for (const auto& l : literals) {
        if (line.find(l) != std::string::npos) found.push_back(rel.string() + ":" + std::to_string(number) + ": " + l);
      }
    }
  }
  for (const auto& f : found) UNSCOPED_INFO(f);
  CHECK(found.empty());
}

TEST_CASE("channel names on the wire", "[contract]") {
  // Logs and lcm-spy sessions name channels by these strings: they must not change.
  CHECK(kTruth == "TRUTH");
  CHECK(kActuatorCommand == "ACTUATOR_CMD");
  CHECK(kActuatorCommandCan == "ACTUATOR_CMD_CAN");
  CHECK(kAttitudeSetpoint == "ATTITUDE_SP");
  CHECK(plant_command_channel(false) == "ACTUATOR_CMD");
  CHECK(plant_command_channel(true) == "ACTUATOR_CMD_CAN");
  CHECK(wall_clock_channels() ==
        std::vector<std::string>{"CAN_HEALTH", "RUN_CONTROL", "HEARTBEAT", "TIMING_HEALTH", "FAULT"});
}

TEST_CASE("nominal rates follow the configured process rates", "[contract]") {
  ProcessRates r;
  r.plant_hz = 1000.0;
  r.truth_hz = 500.0;
  r.feedback_hz = 100.0;
  r.imu_hz = 512.0;
  r.controller_hz = 512.0;
  r.estimator_hz = 512.0;
  SECTION("real time, no motion capture, LCM link") {
    const std::map<std::string, double> expected = {{kTruth, 500.0},
                                                    {kImu, 512.0},
                                                    {kActuatorCommand, 512.0},
                                                    {kAttitudeSetpoint, 512.0},
                                                    {kControllerStatus, 512.0},
                                                    {kEstimate, 512.0},
                                                    {kActuatorFeedback, 100.0},
                                                    {kHeartbeat, 6.0},
                                                    {kTimingHealth, 3.0}};
    const auto hz = expected_rates(r, RunShape{false, 10.0, 3});
    for (const auto& [channel, rate] : expected) {
      INFO(channel);
      const auto it = hz.find(channel);
      REQUIRE(it != hz.end());
      CHECK(it->second == rate);
    }
    // Nothing of the processes and links this run has not (every other periodic channel has a
    // rate in a run with all of them: functional.message_list).
    for (const auto& channel :
         {kMocapPose, kActuatorCommandCan, kActuatorFeedbackCan, kCanHealth, kRigClock, kStepAck}) {
      INFO(channel);
      CHECK(hz.count(channel) == 0);
    }
  }
  SECTION("lockstep over the CAN link") {
    r.estimator_hz = 0.0;
    r.can_link = true;
    r.can_health_hz = 2.0;
    const auto hz = expected_rates(r, RunShape{true, 10.0, 4});
    CHECK(hz.at(kActuatorCommandCan) == 512.0);
    CHECK(hz.at(kActuatorFeedbackCan) == 100.0);
    CHECK(hz.at(kCanHealth) == 4.0);
    // Controller and both bridge sides are due 512 times each, the logger 100 times.
    CHECK(hz.at(kStepAck) == 3 * 512 + 100);
    CHECK(hz.at(kRigClock) >= 512);
    CHECK(hz.at(kRigClock) <= 612);
  }
}

TEST_CASE("the value fields a fault may change, per target channel", "[contract]") {
  // Every double field of the channel's type, in .lcm order, but the estimate's statistics.
  const auto elements = [](const std::string& name, int n) {
    std::vector<std::string> out;
    for (int i = 0; i < n; ++i) out.push_back(name + "[" + std::to_string(i) + "]");
    return out;
  };
  const auto join = [](std::vector<std::vector<std::string>> parts) {
    std::vector<std::string> out;
    for (const auto& p : parts) out.insert(out.end(), p.begin(), p.end());
    return out;
  };
  CHECK(value_field_names(kImu) == join({elements("gyro_radps", 3), elements("accel_mps2", 3), {"temperature_degc"}}));
  CHECK(value_field_names(kMocapPose) ==
        join({elements("position_m", 3), elements("quaternion_wxyz", 4), {"mean_marker_error_m"}}));
  CHECK(value_field_names(kEstimate) ==
        join({elements("euler_rad", 3), elements("velocity_body_mps", 3), elements("gyro_bias_radps", 3),
              elements("accel_bias_mps2", 3), elements("omega_body_radps", 3)}));
  CHECK(value_field_names(kActuatorCommand) ==
        std::vector<std::string>{"flap_freq_left_radps", "flap_freq_right_radps", "delta_f_radps",
                                 "flap_freq_collective_radps", "throttle_pct", "dihedral_rad", "wing_root_rad"});
  CHECK(value_field_names(kActuatorFeedback) ==
        std::vector<std::string>{"flap_freq_left_radps", "flap_freq_right_radps", "delta_f_radps", "dihedral_rad",
                                 "wing_root_rad", "throttle_pct"});
  // Not a fault target: no value fields to change.
  CHECK(value_field_names(kTruth).empty());
  // The addresses are the message's own fields.
  imu_sample_t m{};
  const ValueFields fields = value_fields(m);
  REQUIRE(fields.size() == 7);
  CHECK(fields[0].second == &m.gyro_radps[0]);
  CHECK(fields[6].second == &m.temperature_degc);
}
