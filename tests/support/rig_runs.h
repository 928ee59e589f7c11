#pragma once
/// Test support for system tests: `rig run` of a scenario into a scratch directory, and
/// what tests read back from its log. Needs RIG_BIN (compile definition), LCM and yaml-cpp.

#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <map>
#include <thread>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"
#include "run_rig.h"
#include "scratch.h"

namespace nimble::test {

/// Outcome of one `rig run`.
struct RunResult {
  int exit_code = -1;
  std::string output;  ///< stdout and stderr together
  YAML::Node summary;  ///< the --json summary (null if none was written)
};

/// Runs `rig run <scenario> <args>` to completion, logging to <dir>/run.lcmlog with the
/// summary in <dir>/summary.json and the output in <dir>/out.txt.
inline RunResult rig_run(const std::string& scenario, const std::string& dir, const std::string& args) {
  const std::string out = dir + "/out.txt";
  const std::string json = dir + "/summary.json";
  const std::string cmd = std::string(RIG_BIN) + " run " + scenario + " --log " + dir + "/run.lcmlog --json " + json +
                          " --no-progress " + args + " >" + out + " 2>&1";
  const int status = std::system(cmd.c_str());
  RunResult r;
  r.exit_code = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  r.output = slurp(out);
  if (std::filesystem::exists(json)) r.summary = YAML::LoadFile(json);
  return r;
}

/// Every message of `channel` in a log, as raw bytes (for bit-for-bit comparisons).
inline std::vector<std::vector<uint8_t>> channel_payloads(const std::string& log_path, const std::string& channel) {
  lcm::LogFile log(log_path, "r");
  REQUIRE(log.good());
  std::vector<std::vector<uint8_t>> out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == channel) {
      const auto* b = static_cast<const uint8_t*>(ev->data);
      out.emplace_back(b, b + ev->datalen);
    }
  }
  return out;
}

/// The event timestamps [us] of every message of `channel` in a log.
inline std::vector<int64_t> event_times_us(const std::string& log_path, const std::string& channel) {
  lcm::LogFile log(log_path, "r");
  REQUIRE(log.good());
  std::vector<int64_t> out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel == channel) out.push_back(ev->timestamp);
  }
  return out;
}

/// Every TRUTH message of a log, as raw bytes.
inline std::vector<std::vector<uint8_t>> truth_payloads(const std::string& log_path) {
  return channel_payloads(log_path, contract::channels::kTruth);
}

/// Every message of `channel` in a log, decoded as T (a message that does not decode fails
/// the test).
template <typename T>
std::vector<T> decode_channel(const std::string& log_path, const std::string& channel) {
  lcm::LogFile log(log_path, "r");
  REQUIRE(log.good());
  std::vector<T> out;
  while (const lcm::LogEvent* ev = log.readNextEvent()) {
    if (ev->channel != channel) continue;
    T m{};
    REQUIRE(m.decode(ev->data, 0, ev->datalen) == ev->datalen);
    out.push_back(m);
  }
  return out;
}

/// Number of positions at which two payload sequences differ (sizes must match).
inline std::size_t differing(const std::vector<std::vector<uint8_t>>& a, const std::vector<std::vector<uint8_t>>& b) {
  REQUIRE(a.size() == b.size());
  std::size_t n = 0;
  for (std::size_t i = 0; i < a.size(); ++i) n += a[i] != b[i];
  return n;
}

/// Number of events per channel in a log.
inline std::map<std::string, int> channel_counts(const std::string& log_path) {
  lcm::LogFile log(log_path, "r");
  REQUIRE(log.good());
  std::map<std::string, int> counts;
  while (const lcm::LogEvent* ev = log.readNextEvent()) ++counts[ev->channel];
  return counts;
}

/// Pid of the child of `parent` whose executable is `name`, or -1.
inline pid_t child_named(pid_t parent, const std::string& name) {
  for (const auto& entry : std::filesystem::directory_iterator("/proc")) {
    const std::string pid = entry.path().filename().string();
    if (pid.find_first_not_of("0123456789") != std::string::npos) continue;
    std::ifstream stat(entry.path() / "stat");
    std::string line;
    if (!std::getline(stat, line)) continue;
    const auto close = line.rfind(')');
    const auto open = line.find('(');
    if (open == std::string::npos || close == std::string::npos) continue;
    const std::string comm = line.substr(open + 1, close - open - 1);
    int ppid = 0;
    char state = 0;
    std::sscanf(line.c_str() + close + 2, "%c %d", &state, &ppid);
    if (ppid == parent && comm == name.substr(0, 15)) return static_cast<pid_t>(std::stoi(pid));
  }
  return -1;
}

/// Starts `rig run` in the background; returns its pid.
inline pid_t rig_run_background(const std::string& scenario, const std::string& dir, const std::string& args) {
  const pid_t pid = ::fork();
  if (pid == 0) {
    const std::string out = dir + "/out.txt";
    std::freopen(out.c_str(), "w", stdout);
    std::freopen(out.c_str(), "a", stderr);
    const std::string log = dir + "/run.lcmlog", json = dir + "/summary.json";
    std::vector<std::string> argv_s = {RIG_BIN, "run", scenario, "--log", log, "--json", json, "--no-progress"};
    for (std::size_t start = 0; start < args.size();) {
      const auto end = args.find(' ', start);
      argv_s.push_back(args.substr(start, end - start));
      if (end == std::string::npos) break;
      start = end + 1;
    }
    std::vector<char*> argv;
    for (auto& s : argv_s) argv.push_back(s.data());
    argv.push_back(nullptr);
    ::execv(RIG_BIN, argv.data());
    ::_exit(127);
  }
  return pid;
}

/// Waits (bounded) until `rig run` with pid `rig` has started process `name` and the run
/// has produced TRUTH in its log.
inline pid_t wait_for_running(pid_t rig, const std::string& name, const std::string& log_path) {
  for (int i = 0; i < 600; ++i) {
    const pid_t child = child_named(rig, name);
    if (child > 0 && std::filesystem::exists(log_path) && std::filesystem::file_size(log_path) > 20000) return child;
    std::this_thread::sleep_for(std::chrono::milliseconds(10));
  }
  return -1;
}

inline int wait_exit_code(pid_t pid) {
  int status = 0;
  ::waitpid(pid, &status, 0);
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

}  // namespace nimble::test
