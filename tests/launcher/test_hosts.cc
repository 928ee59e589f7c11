// Unit tests of the hosts section (launcher/hosts.h): placement of the processes on the hosts,
// and every bad input refused with the key it is about and why.

#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "launcher/hosts.h"
#include "launcher/run_plan.h"

using namespace nimble::launcher;
using nimble::ConfigError;
using nimble::Scenario;

namespace {

const std::vector<std::string> kFour = {"plant", "controller", "mocap", "estimator"};

Scenario scenario_with(const std::string& hosts_yaml, const std::vector<std::string>& processes = kFour,
                       const std::string& clock = kClockLockstep) {
  Scenario s;
  s.file = "inline.yaml";
  s.processes = processes;
  s.clock = clock;
  s.root = YAML::Load(hosts_yaml);
  return s;
}

HostPlacement place(const std::string& hosts_yaml, const std::vector<std::string>& processes = kFour,
                    const LaunchConfig& launch = LaunchConfig{}, const std::string& clock = kClockLockstep) {
  return host_placement_from(scenario_with(hosts_yaml, processes, clock), launch);
}

/// Requires that placing `hosts_yaml` fails naming `key` with `problem` in its message.
void expect_error(const std::string& hosts_yaml, const std::string& key, const std::string& problem,
                  const std::vector<std::string>& processes = kFour, const LaunchConfig& launch = LaunchConfig{},
                  const std::string& clock = kClockLockstep) {
  INFO("yaml: " << hosts_yaml);
  try {
    place(hosts_yaml, processes, launch, clock);
    FAIL("expected a ConfigError for " << key);
  } catch (const ConfigError& e) {
    INFO("message: " << e.what());
    CHECK(e.file() == "inline.yaml");
    CHECK(e.key() == key);
    CHECK(std::string(e.what()).find(problem) != std::string::npos);
  }
}

}  // namespace

TEST_CASE("without the section every process runs on the launcher's host", "[unit]") {
  const HostPlacement p = place("name: x");
  CHECK(p.hosts.empty());
  CHECK_FALSE(p.split());
  CHECK(p.host_index("controller") == 0);
}

TEST_CASE("processes placed as listed, the unplaced ones on the first host, in the run's order", "[unit]") {
  const HostPlacement p = place("hosts: {sim: [mocap], flight: [estimator, controller]}");
  REQUIRE(p.hosts.size() == 2);
  CHECK(p.split());
  CHECK(p.hosts[0].name == "sim");
  CHECK(p.hosts[0].processes == std::vector<std::string>{"plant", "mocap"});
  CHECK(p.hosts[1].name == "flight");
  CHECK(p.hosts[1].processes == std::vector<std::string>{"controller", "estimator"});
  CHECK(p.hosts[0].address == "10.76.67.1/30");
  CHECK(p.hosts[1].address == "10.76.67.2/30");
  CHECK(p.host_index("plant") == 0);
  CHECK(p.host_index("estimator") == 1);
  // The mapping form, with the addresses of the link's ends.
  const HostPlacement m = place(
      "hosts: {bench: {processes: [plant], address: 192.168.7.1/24}, "
      "board: {processes: [controller], address: 192.168.7.20/24}}");
  CHECK(m.hosts[0].processes == std::vector<std::string>{"plant", "mocap", "estimator"});
  CHECK(m.hosts[1].address == "192.168.7.20/24");
  // One host only: a placement, but nothing to split.
  const HostPlacement one = place("hosts: {sim: [plant, controller]}");
  REQUIRE(one.hosts.size() == 1);
  CHECK_FALSE(one.split());
  CHECK(one.hosts[0].processes == kFour);
}

TEST_CASE("bad sections are refused naming the key and the problem", "[unit]") {
  expect_error("hosts: [plant]", "hosts", "must be a mapping of host names");
  expect_error("hosts: {}", "hosts", "must be a mapping of host names");
  expect_error("hosts: {a: [plant], b: [controller], c: [mocap]}", "hosts", "at most 2 hosts");
  expect_error("hosts: {'sim pc': [plant], flight: [controller]}", "hosts.sim pc", "letters, digits");
  expect_error("hosts: {sim: [plant], flight: [autopilot]}", "hosts.flight",
               "process 'autopilot' is not one of the run's processes (plant, controller, mocap, estimator)");
  expect_error("hosts: {sim: [plant], flight: [estimator]}", "hosts.flight", "process 'estimator' is not one of",
               {"plant", "controller"});
  expect_error("hosts: {sim: [plant, controller], flight: [controller]}", "hosts.flight",
               "process 'controller' is placed twice (on hosts 'sim' and 'flight')");
  expect_error("hosts: {sim: [plant], flight: [mocap, mocap]}", "hosts.flight",
               "process 'mocap' is placed twice (on host 'flight')");
  expect_error("hosts: {sim: [plant], flight: []}", "hosts.flight", "host 'flight' runs no process");
  expect_error("hosts: {sim: [plant], flight: controller}", "hosts.flight", "must be a list of processes");
  expect_error("hosts: {sim: [plant], flight: {processes: [controller], adress: 10.0.0.2/30}}", "hosts.flight.adress",
               "unknown key");
  expect_error("hosts: {sim: [plant], flight: {address: 10.0.0.2/30}}", "hosts.flight.processes",
               "missing required key");
  expect_error("hosts: {sim: [plant], flight: {processes: [controller], address: 10.0.0.2}}", "hosts.flight.address",
               "IPv4 address with its prefix length");
  expect_error("hosts: {sim: [plant], flight: {processes: [controller], address: 10.0.0.300/30}}",
               "hosts.flight.address", "IPv4 address");
  expect_error("hosts: {sim: [plant], flight: {processes: [controller], address: 10.9.9.2/30}}", "hosts.flight.address",
               "distinct addresses in one subnet (host 'sim' has 10.76.67.1/30)");
  expect_error(
      "hosts: {sim: {processes: [plant], address: 10.0.0.1/30}, flight: {processes: [controller], "
      "address: 10.0.0.1/30}}",
      "hosts.flight.address", "distinct addresses");
  // The CAN bridge's sides share the virtual CAN interface of the launcher's host.
  const std::vector<std::string> with_can = {"plant", "controller", "can_flight", "can_rig"};
  expect_error("hosts: {sim: [plant], flight: [controller, can_flight]}", "hosts.flight",
               "the CAN bridge side 'can_flight' must run on the launcher's host 'sim'", with_can);
  CHECK(place("hosts: {sim: [plant, can_flight, can_rig], flight: [controller]}", with_can).split());
  // Two hosts are two network namespaces on the run's own URL.
  LaunchConfig never;
  never.network_namespace = "never";
  expect_error("hosts: {sim: [plant], flight: [controller]}", "run.network_namespace", "needs run.network_namespace",
               kFour, never);
  LaunchConfig url;
  url.lcm_url = "udpm://239.255.76.67:7667?ttl=0";
  expect_error("hosts: {sim: [plant], flight: [controller]}", "run.lcm_url", "leave run.lcm_url at auto", kFour, url);
  // An emulated host's processes are started by the launcher, in its namespace: none is external.
  LaunchConfig external;
  external.external_processes = {"mocap", "controller"};
  expect_error("hosts: {sim: [plant, mocap], flight: [controller]}", "run.external_processes",
               "process 'controller' runs on the emulated host 'flight'", kFour, external);
  // ... which one host does not need.
  CHECK(place("hosts: {sim: [plant]}", kFour, never).hosts.size() == 1);
}

TEST_CASE("addresses with prefix, and the hint when only the far host is silent", "[unit]") {
  unsigned a = 0;
  int prefix = 0;
  CHECK(parse_ipv4_prefix("10.76.67.2/30", &a, &prefix));
  CHECK(a == 0x0A4C4302u);
  CHECK(prefix == 30);
  for (const char* bad : {"10.76.67.2", "10.76.67.2/31", "10.76.67.2/0", "10.76.67/30", "10.76.67.2/x", "/30", ""}) {
    INFO(bad);
    CHECK_FALSE(parse_ipv4_prefix(bad, &a, &prefix));
  }
  const HostPlacement p = place("hosts: {sim: [plant], flight: [controller, estimator]}");
  CHECK(hosts_hint(p, "controller, estimator").find("all on host 'flight'") != std::string::npos);
  CHECK(hosts_hint(p, "controller, mocap").empty());
  CHECK(hosts_hint(HostPlacement{}, "controller").empty());
}

TEST_CASE("a second host started by hand flies on the lab network's URL, in lockstep", "[unit]") {
  const std::string by_hand =
      "hosts: {sim: [plant, mocap], flight: {processes: [controller, estimator], start: by_hand}}";
  LaunchConfig lab;
  lab.network_namespace = "never";
  lab.lcm_url = "udpm://239.255.76.67:7667?ttl=1";
  const HostPlacement p = place(by_hand, kFour, lab);
  REQUIRE(p.split());
  CHECK_FALSE(p.emulated());
  CHECK(p.started_by_hand("controller"));
  CHECK(p.started_by_hand("estimator"));
  CHECK_FALSE(p.started_by_hand("plant"));
  CHECK(p.hosts[1].by_hand);
  // Its processes are the run's external processes, each once.
  std::vector<std::string> external = {"estimator"};
  add_by_hand_processes(p, external);
  CHECK(external == std::vector<std::string>{"estimator", "controller"});
  std::vector<std::string> none;
  add_by_hand_processes(place("hosts: {sim: [plant], flight: [controller]}"), none);
  CHECK(none.empty());
  CHECK(hosts_hint(p, "controller").find("started by hand") != std::string::npos);
  CHECK(hosts_hint(p, "mocap").empty());
  // An emulated host is not started by hand.
  CHECK(place("hosts: {sim: [plant], flight: [controller]}").emulated());
  CHECK_FALSE(place("hosts: {sim: [plant], flight: [controller]}").started_by_hand("controller"));

  expect_error("hosts: {sim: {processes: [plant], start: by_hand}, flight: [controller]}", "hosts.sim.start",
               "the first host is the launcher's", kFour, lab);
  expect_error("hosts: {sim: [plant], flight: {processes: [controller], start: ssh}}", "hosts.flight.start", "launcher",
               kFour, lab);
  expect_error("hosts: {sim: [plant], flight: {processes: [controller], start: by_hand, address: 10.76.67.2/30}}",
               "hosts.flight.address", "a host started by hand is a machine of the lab network", kFour, lab);
  LaunchConfig in_namespace = lab;
  in_namespace.network_namespace = "auto";
  expect_error(by_hand, "run.network_namespace", "run.network_namespace: never", kFour, in_namespace);
  for (const char* url : {"auto", "udpm://239.255.76.67:7667", "udpm://239.255.76.67:7667?ttl=0",
                          "udpm://239.255.76.67:7667?recv_buf_size=8388608&ttl=0", "udpm://239.255.76.67:7667?ttl=x"}) {
    INFO(url);
    LaunchConfig bad = lab;
    bad.lcm_url = url;
    expect_error(by_hand, "run.lcm_url", "with ttl >= 1", kFour, bad);
  }
  LaunchConfig later_ttl = lab;
  later_ttl.lcm_url = "udpm://239.255.76.67:7667?recv_buf_size=8388608&ttl=2";
  CHECK(place(by_hand, kFour, later_ttl).started_by_hand("controller"));
  expect_error(by_hand, "clock", "fly it in lockstep", kFour, lab, kClockRealtime);
}
