/// The live view of a real-time run as Foxglove sees it: `rig run --clock realtime --foxglove
/// 127.0.0.1:0` with a Foxglove WebSocket client of the protocol's own library
/// (tests/foxglove/node/ws_client.mjs: @foxglove/ws-protocol over `ws`) subscribed to TRUTH and
/// ESTIMATE. What it receives must come at the run's rates and hold the values of the run's log.

#include <catch2/catch.hpp>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <map>
#include <regex>
#include <string>
#include <thread>

#include <nimble/estimator_state_t.hpp>
#include <nimble/truth_state_t.hpp>
#include <nlohmann/json.hpp>

#include "contract/channels.h"
#include "../support/rig_runs.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kEstimate;
using nimble::contract::channels::kTruth;

using namespace nimble;
using nlohmann::json;

namespace {

/// The port `rig run` printed ("live view on ws://127.0.0.1:PORT"), waiting up to 20 s; 0 if none.
int printed_port(const std::string& out_file) {
  const std::regex line("live view on ws://127\\.0\\.0\\.1:([0-9]+)");
  for (int i = 0; i < 2000; ++i) {
    std::smatch m;
    const std::string out = test::slurp(out_file);
    if (std::regex_search(out, m, line)) return std::stoi(m[1]);
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return 0;
}

bool close_to(double a, double b) { return std::fabs(a - b) <= 1e-12 * std::max(1.0, std::fabs(b)); }

/// Received messages of `topic`: the rate of their rig timestamps [Hz] over their span, checking
/// each payload's values against the log's message with the same utime (`values`: utime -> the
/// roll angle and the roll rate).
double check_topic(const json& received, const std::map<int64_t, std::pair<double, double>>& values,
                   const std::string& topic) {
  const json& list = received["messages"][topic];
  INFO(topic);
  REQUIRE(list.size() > 10);
  std::size_t mismatches = 0;
  for (const json& m : list) {
    const int64_t utime = m["msg"]["utime"].get<int64_t>();
    const auto it = values.find(utime);
    if (it == values.end() || !close_to(m["msg"]["euler_rad"][0].get<double>(), it->second.first) ||
        !close_to(m["msg"]["omega_body_radps"][0].get<double>(), it->second.second)) {
      ++mismatches;
    }
  }
  CHECK(mismatches == 0);
  const double first_s = std::stod(list.front()["t_ns"].get<std::string>()) / 1e9;
  const double last_s = std::stod(list.back()["t_ns"].get<std::string>()) / 1e9;
  REQUIRE(last_s > first_s);
  return static_cast<double>(list.size() - 1) / (last_s - first_s);
}

}  // namespace

TEST_CASE(
    "live view of a real-time hover run: Foxglove's client gets TRUTH and ESTIMATE at the run's rates with "
    "the log's values",
    "[system][foxglove]") {
  const std::string npm = NPM_DIR;
  if (!std::filesystem::exists(npm + "/node_modules/@foxglove/ws-protocol") ||
      !std::filesystem::exists(npm + "/node_modules/ws")) {
    FAIL("no npm packages in " << npm << "/node_modules: run scripts/setup.sh");
  }
  const std::string dir = test::scratch_dir("foxglove_live");
  const pid_t rig = test::rig_run_background(std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml", dir,
                                             "--clock realtime --set duration_s=3 --foxglove 127.0.0.1:0");
  const int port = printed_port(dir + "/out.txt");
  const std::string client_json = dir + "/client.json";
  int client_code = -1;
  if (port > 0) {
    const std::string cmd = "node " + npm + "/ws_client.mjs --url ws://127.0.0.1:" + std::to_string(port) +
                            " --topics TRUTH,ESTIMATE --seconds 1.5 --connect-timeout 20 --out " + client_json + " >" +
                            dir + "/client.txt 2>&1";
    const int status = std::system(cmd.c_str());
    client_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  const int rig_code = test::wait_exit_code(rig);
  INFO("rig run output:\n" << test::slurp(dir + "/out.txt") << "\nclient:\n" << test::slurp(dir + "/client.txt"));
  REQUIRE(port > 0);
  REQUIRE(rig_code == 0);
  REQUIRE(client_code == 0);

  const json received = json::parse(test::slurp(client_json));
  CHECK(received["subprotocol"] == "foxglove.websocket.v1");
  CHECK(received["channels"][kTruth]["schemaName"] == "nimble.truth_state_t");
  CHECK(received["channels"][kEstimate]["encoding"] == "json");
  CHECK(received["statuses"].empty());

  const std::string log = dir + "/run.lcmlog";
  std::map<int64_t, std::pair<double, double>> truth, estimate;
  for (const auto& t : test::decode_channel<truth_state_t>(log, contract::channels::kTruth)) {
    truth[t.utime] = {t.euler_rad[0], t.omega_body_radps[0]};
  }
  for (const auto& e : test::decode_channel<estimator_state_t>(log, contract::channels::kEstimate)) {
    estimate[e.utime] = {e.euler_rad[0], e.omega_body_radps[0]};
  }
  // TRUTH is stamped with its own rig time.
  for (const json& m : received["messages"][kTruth]) {
    REQUIRE(std::stoll(m["t_ns"].get<std::string>()) == m["msg"]["utime"].get<int64_t>() * 1000);
  }

  const YAML::Node summary = YAML::LoadFile(dir + "/summary.json");
  const double sim_s = summary["sim_time_s"].as<double>();
  const double truth_hz = summary["channels"][kTruth]["count"].as<double>() / sim_s;
  const double estimate_hz = summary["channels"][kEstimate]["count"].as<double>() / sim_s;
  const double got_truth_hz = check_topic(received, truth, kTruth);
  const double got_estimate_hz = check_topic(received, estimate, kEstimate);
  INFO("TRUTH " << got_truth_hz << " Hz received, " << truth_hz << " Hz in the log; ESTIMATE " << got_estimate_hz
                << " Hz, " << estimate_hz << " Hz");
  CHECK(std::fabs(got_truth_hz / truth_hz - 1.0) < 0.03);
  CHECK(std::fabs(got_estimate_hz / estimate_hz - 1.0) < 0.03);

  const YAML::Node live = summary["live_view"];
  REQUIRE(live);
  CHECK(live["clients"].as<int>() == 1);
  CHECK(live["messages_sent"].as<long long>() >=
        static_cast<long long>(received["messages"][kTruth].size() + received["messages"][kEstimate].size()));
  CHECK(live["dropped"].as<long long>() == 0);
  CHECK(live["refused"].as<long long>() == 0);
  CHECK(live["protocol_errors"].as<long long>() == 0);
  std::filesystem::remove_all(dir);
}
