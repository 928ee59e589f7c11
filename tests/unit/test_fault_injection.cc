// The fault injector at the publisher (transport/fault_injector.h), the faults section's reader
// (scenario/fault_section.h) and the estimator's divergence monitor (estimator/divergence_monitor.h).

#include <cmath>
#include <fstream>
#include <regex>
#include <limits>
#include <random>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/imu_sample_t.hpp>
#include <yaml-cpp/yaml.h>

#include "contract/channels.h"
#include "contract/decode.h"
#include "core/config.h"
#include "estimator/divergence_monitor.h"
#include "scenario/fault_section.h"
#include "transport/bus.h"
#include "transport/inprocess_hub.h"

namespace {

using nimble::contract::FaultKind;
using nimble::contract::FaultSpec;
const std::string& kImu = nimble::contract::channels::kImu;

/// What a subscriber of IMU received: decoded messages, and how many did not decode.
struct Received {
  std::vector<nimble::imu_sample_t> messages;
  int malformed = 0;
};

/// Publishes `n` IMU samples 1 ms apart (gyro x = i) through a Bus with `faults`; returns what arrived.
Received publish_through(const std::vector<FaultSpec>& faults, int n = 100, uint64_t seed = 1) {
  nimble::transport::InprocessHub hub;
  Received got;
  // As every receiver does (transport::Bus): exactly one message, continuing the sequence.
  int64_t last_seq = -1;
  hub.subscribe(kImu, [&](const std::string&, const void* data, int size) {
    nimble::imu_sample_t m{};
    if (nimble::contract::decode_exact(data, size, m) && nimble::contract::seq_continues(last_seq, m.seq)) {
      got.messages.push_back(m);
      last_seq = m.seq;
    } else {
      ++got.malformed;
    }
  });
  nimble::transport::Bus bus(hub);
  int announced = 0;
  bus.set_fault_injector(std::make_unique<nimble::transport::FaultInjector>(
      faults, seed, [&](const FaultSpec&, bool, int64_t) { ++announced; }));
  for (int i = 0; i < n; ++i) {
    nimble::imu_sample_t m{};
    m.utime = 1000 * i;
    m.seq = 1000 + i;  // the injector owns the seq of a faulted channel
    m.gyro_radps[0] = i;
    m.accel_mps2[2] = -9.81;
    bus.publish(kImu, m);
    hub.drain();
  }
  if (!faults.empty()) CHECK(announced >= 1);
  return got;
}

FaultSpec fault(FaultKind kind, int64_t start_us, int64_t end_us) {
  FaultSpec f;
  f.target = kImu;
  f.kind = kind;
  f.start_us = start_us;
  f.end_us = end_us;
  return f;
}

bool seq_contiguous(const std::vector<nimble::imu_sample_t>& m) {
  for (std::size_t i = 0; i < m.size(); ++i) {
    if (m[i].seq != static_cast<int64_t>(i)) return false;
  }
  return true;
}

}  // namespace

TEST_CASE("fault injector: off sends nothing in its window and leaves no gap in seq", "[fault_injector]") {
  const Received r = publish_through({fault(FaultKind::kOff, 20000, 30000)});
  REQUIRE(r.messages.size() == 90);
  CHECK(seq_contiguous(r.messages));
  for (const auto& m : r.messages) CHECK((m.utime < 20000 || m.utime >= 30000));
}

TEST_CASE("fault injector: stuck repeats the last message before it with fresh stamps", "[fault_injector]") {
  const Received r = publish_through({fault(FaultKind::kStuck, 20000, 30000)});
  REQUIRE(r.messages.size() == 100);
  CHECK(seq_contiguous(r.messages));
  for (int i = 20; i < 30; ++i) {
    CHECK(r.messages[static_cast<std::size_t>(i)].gyro_radps[0] == 19.0);
    CHECK(r.messages[static_cast<std::size_t>(i)].utime == 1000 * i);
  }
  CHECK(r.messages[30].gyro_radps[0] == 30.0);
}

TEST_CASE("fault injector: garbage bytes are refused by receivers, garbage nan replaces exactly the fields asked",
          "[fault_injector]") {
  const Received bytes = publish_through({fault(FaultKind::kGarbage, 20000, 30000)});
  CHECK(bytes.malformed == 10);
  CHECK(bytes.messages.size() == 90);
  CHECK(seq_contiguous(bytes.messages));  // malformed bytes carry no seq
  FaultSpec nan = fault(FaultKind::kGarbage, 20000, 30000);
  nan.garbage_nan = true;
  nan.field = "gyro_radps";
  const Received r = publish_through({nan});
  REQUIRE(r.messages.size() == 100);
  CHECK(std::isnan(r.messages[25].gyro_radps[2]));
  CHECK(r.messages[25].accel_mps2[2] == -9.81);
  CHECK(r.messages[25].utime == 25000);
}

TEST_CASE("fault injector: wrong scales and biases the selected field only", "[fault_injector]") {
  FaultSpec f = fault(FaultKind::kWrong, 0, 1000000);
  f.field = "gyro_radps[0]";
  f.scale = 2.0;
  f.bias = 0.5;
  const Received r = publish_through({f});
  REQUIRE(r.messages.size() == 100);
  CHECK(r.messages[10].gyro_radps[0] == 20.5);
  CHECK(r.messages[10].accel_mps2[2] == -9.81);
}

TEST_CASE("fault injector: slow publishes one in divisor without gaps", "[fault_injector]") {
  FaultSpec f = fault(FaultKind::kSlow, 0, 1000000);
  f.divisor = 4;
  const Received r = publish_through({f});
  REQUIRE(r.messages.size() == 25);
  CHECK(seq_contiguous(r.messages));
  CHECK(r.messages[1].utime == 4000);
}

TEST_CASE("fault injector: delayed keeps order and seq, each message delay later", "[fault_injector]") {
  FaultSpec f = fault(FaultKind::kDelayed, 20000, 30000);
  f.delay_us = 5000;
  nimble::transport::InprocessHub hub;
  std::vector<std::pair<int64_t, int64_t>> arrivals;  // (publish step, message utime)
  int64_t step = 0;
  hub.subscribe(kImu, [&](const std::string&, const void* data, int size) {
    nimble::imu_sample_t m{};
    REQUIRE(nimble::contract::decode_exact(data, size, m));
    arrivals.emplace_back(step, m.utime);
  });
  nimble::transport::Bus bus(hub);
  bus.set_fault_injector(std::make_unique<nimble::transport::FaultInjector>(std::vector<FaultSpec>{f}, 1, nullptr));
  for (step = 0; step < 100; ++step) {
    nimble::imu_sample_t m{};
    m.utime = 1000 * step;
    bus.publish(kImu, m);
    hub.drain();
  }
  REQUIRE(arrivals.size() == 100);
  for (std::size_t i = 1; i < arrivals.size(); ++i) CHECK(arrivals[i].second > arrivals[i - 1].second);
  for (const auto& [at, utime] : arrivals) {
    if (utime >= 20000 && utime < 30000) CHECK(at * 1000 == utime + 5000);
  }
}

TEST_CASE("fault injector: intermittent loses with its probability, a gap in seq, the same for the same seed",
          "[fault_injector]") {
  FaultSpec f = fault(FaultKind::kIntermittent, 0, 100000000);
  f.probability = 0.3;
  const Received a = publish_through({f}, 10000, 7);
  const Received b = publish_through({f}, 10000, 7);
  const Received c = publish_through({f}, 10000, 8);
  // Binomial(10000, 0.3): 3000 +- 46 lost.
  CHECK(10000 - static_cast<int>(a.messages.size()) == Approx(3000).margin(5 * 46));
  // Lost on the way: each lost message leaves its seq unused, a gap receivers count as a drop.
  bool seq_is_position = true;
  for (const auto& m : a.messages) seq_is_position = seq_is_position && m.seq == m.utime / 1000;
  CHECK(seq_is_position);
  REQUIRE(a.messages.size() == b.messages.size());
  for (std::size_t i = 0; i < a.messages.size(); ++i) CHECK(a.messages[i].seq == b.messages[i].seq);
  CHECK(c.messages.size() != a.messages.size());
}

TEST_CASE("faults section: entries are read, bad ones named by their key", "[fault_injector]") {
  const std::vector<std::string> processes = {"plant", "controller", "estimator", "mocap"};
  const YAML::Node good = YAML::Load(
      "[{target: IMU, kind: delayed, start_s: 1, duration_s: 0.5, params: {delay_ms: 20}},"
      " {target: ESTIMATE, kind: off, start_s: 2}]");
  const auto faults = nimble::faults_from(good, "s.yaml", processes, false, 5.0);
  REQUIRE(faults.size() == 2);
  CHECK(faults[0].kind == FaultKind::kDelayed);
  CHECK(faults[0].delay_us == 20000);
  CHECK(faults[0].end_us == 1500000);
  CHECK(faults[1].index == 1);
  CHECK(faults[1].end_us == std::numeric_limits<int64_t>::max());
  CHECK(faults[1].describe().find("ESTIMATE off") != std::string::npos);

  const auto error_of = [&](const std::string& text, const std::vector<std::string>& procs) -> std::string {
    try {
      nimble::faults_from(YAML::Load(text), "s.yaml", procs, false, 5.0);
    } catch (const nimble::ConfigError& e) {
      return e.what();
    }
    return "";
  };
  CHECK(error_of("[{target: IMU, kind: off, start_s: 1, extra: 2}]", processes).find("extra") != std::string::npos);
  CHECK(error_of("[{target: IMU, kind: intermittent, start_s: 1, params: {probability: 1.5}}]", processes)
            .find("faults[0].params.probability") != std::string::npos);
  CHECK(error_of("[{target: MOCAP_POSE, kind: off, start_s: 1}]", {"plant", "controller"})
            .find("published by the mocap") != std::string::npos);
  CHECK(error_of("{target: IMU}", processes).find("must be a list") != std::string::npos);
  CHECK(error_of("[{target: IMU, kind: wrong, start_s: 1}]", processes).find("scale other than 1") !=
        std::string::npos);
}

TEST_CASE("divergence monitor: the threshold follows from the gate and the false-alarm rate", "[divergence]") {
  // P(Binomial(40, 0.001) >= k): 5 is the first below 1e-9.
  CHECK(nimble::DivergenceMonitor::binomial_tail(40, 0.001, 4) > 1e-9);
  CHECK(nimble::DivergenceMonitor::binomial_tail(40, 0.001, 5) <= 1e-9);
  CHECK(nimble::DivergenceMonitor::binomial_tail(3, 0.5, 2) == Approx(0.5));
  const nimble::DivergenceMonitor m(40, 0.001, 1e-9);
  CHECK(m.threshold() == 5);
}

TEST_CASE("divergence monitor: no alarm on a consistent filter over many seeds and a quick one on a diverged filter",
          "[divergence]") {
  // A consistent filter: rejections independent with q = 0.001. 20 seeds x 200,000 decisions
  // (5.5 hours of motion capture at 200 Hz): the false-alarm rate 1e-9 per window predicts
  // 0.004 alarms in all; none may come.
  int alarms = 0;
  for (uint64_t seed = 1; seed <= 20; ++seed) {
    std::mt19937_64 rng(seed);
    std::bernoulli_distribution reject(0.001);
    nimble::DivergenceMonitor m(40, 0.001, 1e-9);
    for (int i = 0; i < 200000; ++i) alarms += m.add(reject(rng)) ? 1 : 0;
  }
  CHECK(alarms == 0);
  // Diverged: every measurement fails the gate; declared after 5.
  nimble::DivergenceMonitor m(40, 0.001, 1e-9);
  int n = 0;
  while (!m.add(true)) ++n;
  CHECK(n + 1 == 5);
}

TEST_CASE("fault code names: every CODE_ constant of fault_event_t.lcm has its name", "[fault_injector]") {
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/lcmtypes/fault_event_t.lcm");
  REQUIRE(in.good());
  const std::regex constant(R"(const\s+int32_t\s+CODE_(\w+)\s*=\s*(\d+)\s*;)");
  std::string line;
  int checked = 0;
  while (std::getline(in, line)) {
    std::smatch m;
    if (!std::regex_search(line, m, constant)) continue;
    CHECK(nimble::contract::fault_code_name(std::stoi(m[2])) == m[1].str());
    ++checked;
  }
  CHECK(checked >= 19);
  CHECK(nimble::contract::fault_code_name(999) == "code 999");
}

TEST_CASE(
    "fault kinds: one list names every kind once, in the enumeration's order, and docs/faults.md lists each with "
    "its parameters",
    "[fault_injector]") {
  const auto& kinds = nimble::contract::fault_kinds();
  REQUIRE(kinds.size() == static_cast<std::size_t>(FaultKind::kCanBusOff) + 1);
  std::ifstream in(std::string(RIG_SOURCE_DIR) + "/docs/faults.md");
  REQUIRE(in.good());
  const std::string doc((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  for (std::size_t i = 0; i < kinds.size(); ++i) {
    INFO(kinds[i].name);
    CHECK(static_cast<std::size_t>(kinds[i].kind) == i);
    CHECK(std::string(nimble::contract::fault_kind_name(kinds[i].kind)) == kinds[i].name);
    for (std::size_t j = 0; j < i; ++j) CHECK(std::string(kinds[j].name) != kinds[i].name);
    // Each kind is accepted by the scenario loader on its own kind of target, with no parameter
    // when it takes none.
    const bool can = kinds[i].target == nimble::contract::FaultTarget::kCanLink;
    if (std::string(kinds[i].params).empty()) {
      const auto f = nimble::faults_from(
          YAML::Load("[{target: " + (can ? nimble::contract::kFaultTargetCan : nimble::contract::channels::kImu) +
                     ", kind: " + kinds[i].name + ", start_s: 1}]"),
          "s.yaml", {"plant", "controller", "estimator", "mocap", "can_flight", "can_rig"}, can, 5.0);
      REQUIRE(f.size() == 1);
      CHECK(f[0].kind == kinds[i].kind);
    }
    // The documentation's table of kinds has its row: "| `name` |".
    CHECK(doc.find(std::string("| `") + kinds[i].name + "`") != std::string::npos);
  }
}
