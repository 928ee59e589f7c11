// Unit tests of parameter tables (core/param_table.h): one declaration drives the loader, the
// validation of a struct built in code, and the documentation.

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <string>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "core/param_table.h"

using namespace nimble;

namespace {

struct Toy {
  double rate_hz = 512.0;
  Eigen::Vector3d sigma = Eigen::Vector3d(0.1, 0.2, 0.3);
  bool enabled = true;
  int count = 4;
  std::int64_t latency_us = 5000;
};

const ParamTable<Toy>& toy_params() {
  static const ParamTable<Toy> table = {
      {"rate_hz", &Toy::rate_hz, Range{0.0, 1e5, true, false}, "Hz", "output rate"},
      {"sigma", &Toy::sigma, Range::non_negative(), "rad/s", "noise"},
      {"enabled", &Toy::enabled, Range::any(), "-", "on or off"},
      {"count", &Toy::count, Range::closed(0, 10), "-", "how many"},
      {"latency_us", &Toy::latency_us, Range::closed(0, 1e6), "us", "delay"},
  };
  return table;
}

Toy load(const std::string& yaml) {
  const YAML::Node node = YAML::Load(yaml);
  ConfigMap map(node, "toy.yaml", "toy");
  Toy t;
  read_params(map, toy_params(), t);
  map.finish();
  return t;
}

}  // namespace

TEST_CASE("param table: absent keys keep the struct's defaults, present ones are read", "[config]") {
  const Toy d = load("{}");
  CHECK(d.rate_hz == 512.0);
  CHECK(d.sigma == Eigen::Vector3d(0.1, 0.2, 0.3));
  const Toy t = load("{rate_hz: 200, sigma: {y: 0.5}, enabled: false, count: 7, latency_us: 12}");
  CHECK(t.rate_hz == 200.0);
  CHECK(t.sigma == Eigen::Vector3d(0.1, 0.5, 0.3));
  CHECK_FALSE(t.enabled);
  CHECK(t.count == 7);
  CHECK(t.latency_us == 12);
}

TEST_CASE("param table: the loader refuses what the range refuses, naming file, key and value", "[config]") {
  CHECK_THROWS_WITH(load("{rate_hz: 0}"),
                    Catch::Contains("toy.yaml") && Catch::Contains("rate_hz") && Catch::Contains("0"));
  CHECK_THROWS_WITH(load("{sigma: {z: -1}}"), Catch::Contains("sigma.z"));
  CHECK_THROWS_WITH(load("{count: 11}"), Catch::Contains("count"));
  CHECK_THROWS_WITH(load("{count: 1.5}"), Catch::Contains("count"));
  CHECK_THROWS_WITH(load("{rate_hz: 100, speling: 1}"), Catch::Contains("speling"));
}

TEST_CASE("param table: a struct built in code is checked against the same ranges", "[config]") {
  Toy t;
  CHECK_NOTHROW(check_params(toy_params(), t));
  t.rate_hz = -1.0;
  const std::string rate_range = Range{0.0, 1e5, true, false}.describe();
  CHECK_THROWS_WITH(check_params(toy_params(), t), "rate_hz = -1: must be " + rate_range);
  t = Toy{};
  t.sigma.y() = std::nan("");
  CHECK_THROWS_WITH(check_params(toy_params(), t), Catch::StartsWith("sigma[1] = nan"));
  t = Toy{};
  t.latency_us = 2000000;
  CHECK_THROWS_WITH(check_params(toy_params(), t), Catch::StartsWith("latency_us = 2000000"));
}

TEST_CASE("param table: the documentation shows each key with its default, range, unit and meaning", "[config]") {
  const std::string md = params_markdown(toy_params(), Toy{}, "toy.");
  CHECK(md.find("| key | default | allowed | unit | meaning |") == 0);
  const std::string rate_row =
      "| `toy.rate_hz` | 512 | " + Range{0.0, 1e5, true, false}.describe() + " | Hz | output rate |";
  CHECK(md.find(rate_row) != std::string::npos);
  CHECK(md.find("| `toy.sigma` | {x: 0.1, y: 0.2, z: 0.3} |") != std::string::npos);
  CHECK(md.find("| `toy.enabled` | true | true, false | - | on or off |") != std::string::npos);
  CHECK(std::count(md.begin(), md.end(), '\n') == 2 + 5);
}
