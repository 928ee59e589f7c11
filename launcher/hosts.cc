#include "launcher/hosts.h"

#include <arpa/inet.h>
#include <unistd.h>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <map>

#include "can_bridge/bridge_config.h"
#include "launcher/netns.h"
#include "launcher/run_plan.h"
#include "launcher/run_report.h"

namespace nimble::launcher {
namespace {

/// A host name shows in the summary, the JSON report and error messages: letters, digits, '-'
/// and '_', at most this many.
constexpr std::size_t kMaxHostNameLength = 32;

bool valid_host_name(const std::string& name) {
  if (name.empty() || name.size() > kMaxHostNameLength) return false;
  return std::all_of(name.begin(), name.end(),
                     [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '-' || c == '_'; });
}

std::string join(const std::vector<std::string>& items) {
  std::string out;
  for (const auto& i : items) out += (out.empty() ? "" : ", ") + i;
  return out;
}

unsigned subnet_of(unsigned address, int prefix) { return prefix == 0 ? 0u : address & (~0u << (32 - prefix)); }

/// The ttl of an LCM udpm URL (LCM's default, 0, when the URL gives none); -1 if it is not a number.
int lcm_url_ttl(const std::string& url) {
  const auto at = url.find("ttl=");
  if (at == std::string::npos || (at > 0 && url[at - 1] != '?' && url[at - 1] != '&')) return 0;
  const auto end = url.find('&', at);
  const std::string digits = url.substr(at + 4, end == std::string::npos ? std::string::npos : end - at - 4);
  if (digits.empty() || digits.size() > 3 || !std::all_of(digits.begin(), digits.end(), ::isdigit)) return -1;
  return std::atoi(digits.c_str());
}

}  // namespace

std::size_t HostPlacement::host_index(const std::string& process) const {
  for (std::size_t i = 0; i < hosts.size(); ++i) {
    if (std::find(hosts[i].processes.begin(), hosts[i].processes.end(), process) != hosts[i].processes.end()) return i;
  }
  return 0;
}

bool parse_ipv4_prefix(const std::string& text, unsigned* address, int* prefix) {
  const auto slash = text.find('/');
  if (slash == std::string::npos) return false;
  in_addr a{};
  if (::inet_pton(AF_INET, text.substr(0, slash).c_str(), &a) != 1) return false;
  const std::string bits = text.substr(slash + 1);
  if (bits.empty() || bits.size() > 2 || !std::all_of(bits.begin(), bits.end(), ::isdigit)) return false;
  const int n = std::atoi(bits.c_str());
  if (n < 1 || n > 30) return false;
  *address = ntohl(a.s_addr);
  *prefix = n;
  return true;
}

namespace {

/// One host of the hosts: section, the `i`th: its name, address and how it is started; each of its
/// processes is entered in `placed` (process -> host).
HostConfig read_host(const Scenario& scenario, ConfigMap& section, const std::string& name, std::size_t i,
                     std::map<std::string, std::string>& placed) {
  if (!valid_host_name(name)) {
    section.fail(name, "host name '" + name + "' must be 1 to " + std::to_string(kMaxHostNameLength) +
                           " letters, digits, '-' or '_'");
  }
  HostConfig host;
  host.name = name;
  host.address = kDefaultHostAddresses[i];
  std::vector<std::string> listed;
  const YAML::Node node = scenario.root["hosts"][name];
  std::string list_key = section.key_path(name);
  if (node.IsSequence()) {
    listed = section.get_string_list(name);
  } else if (node.IsMap()) {
    ConfigMap host_map = section.get_map(name);
    listed = host_map.get_string_list("processes");
    list_key = host_map.key_path("processes");
    if (host_map.has("start")) host.by_hand = host_map.get_enum("start", {"launcher", "by_hand"}) == "by_hand";
    if (host.by_hand && i == 0) {
      host_map.fail("start", "the first host is the launcher's: its processes are started by the launcher");
    }
    if (host.by_hand && host_map.has("address")) {
      host_map.fail("address",
                    "is the address of the emulated link's end; a host started by hand is a machine of "
                    "the lab network with its own address");
    }
    if (host_map.has("address")) {
      host.address = host_map.get_string("address");
      unsigned a = 0;
      int prefix = 0;
      if (!parse_ipv4_prefix(host.address, &a, &prefix)) {
        host_map.fail("address", "must be an IPv4 address with its prefix length (1 to 30), e.g. 10.76.67.2/30");
      }
    }
    host_map.finish();
  } else {
    section.fail(name,
                 "must be a list of processes, e.g. [controller, estimator], or a mapping with "
                 "processes: (and address: or start:)");
  }
  for (const auto& p : listed) {
    if (!scenario.runs(p)) {
      throw ConfigError(scenario.file, list_key, p,
                        "process '" + p + "' is not one of the run's processes (" + join(scenario.processes) + ")");
    }
    const auto [it, fresh] = placed.emplace(p, name);
    if (!fresh) {
      throw ConfigError(
          scenario.file, list_key, p,
          "process '" + p + "' is placed twice (" +
              (it->second == name ? "on host '" + name + "'" : "on hosts '" + it->second + "' and '" + name + "'") +
              ")");
    }
  }
  if (listed.empty() && i > 0) {
    throw ConfigError(scenario.file, list_key, "[]", "host '" + name + "' runs no process");
  }
  return host;
}

/// The checks of a run over two hosts: the link's addresses, the CAN bridge's sides, and the
/// launcher's settings for a second host started by hand or emulated.
void check_two_hosts(const Scenario& scenario, const LaunchConfig& launch, const HostPlacement& placement,
                     const std::map<std::string, std::string>& placed) {
  const HostConfig& first = placement.hosts[0];
  const HostConfig& second = placement.hosts[1];
  if (!second.by_hand) {
    unsigned a0 = 0, a1 = 0;
    int p0 = 0, p1 = 0;
    parse_ipv4_prefix(first.address, &a0, &p0);
    parse_ipv4_prefix(second.address, &a1, &p1);
    if (p0 != p1 || subnet_of(a0, p0) != subnet_of(a1, p1) || a0 == a1) {
      throw ConfigError(scenario.file, "hosts." + second.name + ".address", second.address,
                        "the two ends of the link need distinct addresses in one subnet (host '" + first.name +
                            "' has " + first.address + ")");
    }
  }
  for (const std::string& side : {can::kFlightProcess, can::kRigProcess}) {
    const auto it = placed.find(side);
    if (it != placed.end() && it->second != first.name) {
      throw ConfigError(scenario.file, "hosts." + it->second, side,
                        "the CAN bridge side '" + side + "' must run on the launcher's host '" + first.name +
                            "' (the first in hosts): the run's virtual CAN interface is created in "
                            "that host's network namespace, and a vcan cannot span two hosts");
    }
  }
  if (second.by_hand) {
    // A real second machine: the launcher flies on the lab network, in lockstep.
    const std::string where = "host '" + second.name + "' is started by hand (a machine of the lab network)";
    if (launch.network_namespace != "never") {
      throw ConfigError(scenario.file, "run.network_namespace", launch.network_namespace,
                        where + ": the launcher must be on the lab network too, run.network_namespace: never");
    }
    if (launch.lcm_url == "auto" || lcm_url_ttl(launch.lcm_url) < 1) {
      throw ConfigError(scenario.file, "run.lcm_url", launch.lcm_url,
                        where +
                            ": give the lab network's URL, with ttl >= 1 so that the datagrams leave this "
                            "machine, e.g. udpm://239.255.76.67:7667?ttl=1");
    }
    if (scenario.clock == kClockRealtime) {
      throw ConfigError(scenario.file, "clock", scenario.clock,
                        where +
                            ": fly it in lockstep; in real time every process keeps the start time, the "
                            "launcher's CLOCK_MONOTONIC, which another machine does not share");
    }
    return;
  }
  for (const auto& p : launch.external_processes) {
    if (placement.host_index(p) > 0) {
      throw ConfigError(scenario.file, "run.external_processes", p,
                        "process '" + p + "' runs on the emulated host '" + second.name +
                            "', whose processes the "
                            "launcher starts in that host's network namespace (on two real machines: start: by_hand)");
    }
  }
  if (launch.network_namespace == "never") {
    throw ConfigError(scenario.file, "run.network_namespace", "never",
                      "a run over two hosts emulates them as two network namespaces joined by a veth pair: it "
                      "needs run.network_namespace auto or always (or start: by_hand on two real machines)");
  }
  if (launch.lcm_url != "auto") {
    throw ConfigError(scenario.file, "run.lcm_url", launch.lcm_url,
                      std::string("a run over two emulated hosts flies on its own URL across the emulated link (") +
                          kTwoHostLcmUrl + "): leave run.lcm_url at auto (or start: by_hand on two real machines)");
  }
}

}  // namespace

HostPlacement host_placement_from(const Scenario& scenario, const LaunchConfig& launch) {
  HostPlacement placement;
  if (!scenario.has_section("hosts")) return placement;
  const std::string usage =
      "must be a mapping of host names to the processes each runs, e.g. "
      "{sim: [plant, mocap], flight: [controller, estimator]}";
  if (!scenario.root["hosts"].IsMap()) {
    throw ConfigError(scenario.file, "hosts", yaml_text(scenario.root["hosts"]), usage);
  }
  ConfigMap section(scenario.root["hosts"], scenario.file, "hosts");
  const std::vector<std::string> names = section.keys();
  if (names.empty()) throw ConfigError(scenario.file, "hosts", "{}", usage);
  if (names.size() > kMaxHosts) {
    throw ConfigError(
        scenario.file, "hosts", join(names),
        "at most " + std::to_string(kMaxHosts) + " hosts (the launcher's and one other, joined by one emulated link)");
  }
  std::map<std::string, std::string> placed;  // process -> host
  for (std::size_t i = 0; i < names.size(); ++i) {
    placement.hosts.push_back(read_host(scenario, section, names[i], i, placed));
  }
  section.finish();
  // Each host's processes in the order of the scenario; the unplaced ones on the launcher's host.
  for (const auto& p : scenario.processes) {
    const auto it = placed.find(p);
    const std::string& host = it == placed.end() ? names.front() : it->second;
    for (auto& h : placement.hosts) {
      if (h.name == host) h.processes.push_back(p);
    }
  }
  if (!placement.split()) return placement;
  check_two_hosts(scenario, launch, placement, placed);
  return placement;
}

std::unique_ptr<HostLink> link_hosts(const HostPlacement& placement, bool in_private_namespace, std::string* problem) {
  if (!placement.emulated()) {
    *problem = "the run has no emulated second host";
    return nullptr;
  }
  if (!in_private_namespace) {
    *problem =
        "a run over two hosts emulates them as network namespaces, and the launcher could not make its own "
        "(it needs root or unprivileged user namespaces)";
    return nullptr;
  }
  return HostLink::create(placement.hosts[0].address, placement.hosts[1].address, problem);
}

void add_by_hand_processes(const HostPlacement& placement, std::vector<std::string>& external) {
  if (!placement.split() || !placement.hosts[1].by_hand) return;
  for (const auto& p : placement.hosts[1].processes) {
    if (std::find(external.begin(), external.end(), p) == external.end()) external.push_back(p);
  }
}

std::vector<HostSummary> host_summaries(const HostPlacement& placement, const HostLink* link) {
  std::vector<HostSummary> out;
  for (std::size_t i = 0; i < placement.hosts.size(); ++i) {
    const HostConfig& h = placement.hosts[i];
    HostSummary s;
    s.name = h.name;
    s.launcher = i == 0;
    s.processes = h.processes;
    if (placement.emulated()) s.address = h.address;
    if (i == 0) {
      char id[64] = {0};
      const ssize_t n = ::readlink("/proc/self/ns/net", id, sizeof id - 1);
      if (n > 0) s.network_namespace.assign(id, static_cast<std::size_t>(n));
    } else if (link != nullptr) {
      s.network_namespace = link->remote_namespace_id();
    }
    out.push_back(s);
  }
  return out;
}

std::string hosts_hint(const HostPlacement& placement, const std::string& waiting) {
  if (!placement.split() || waiting.empty()) return "";
  if (placement.hosts[1].by_hand) {
    for (std::size_t start = 0; start < waiting.size();) {
      const auto end = waiting.find(", ", start);
      if (placement.started_by_hand(waiting.substr(start, end - start))) {
        return " (host '" + placement.hosts[1].name +
               "' is started by hand: were its processes started there, "
               "with the resolved scenario and this run's URL, and does multicast cross the lab network both ways?)";
      }
      if (end == std::string::npos) break;
      start = end + 2;
    }
    return "";
  }
  for (std::size_t start = 0; start < waiting.size();) {
    const auto end = waiting.find(", ", start);
    if (placement.host_index(waiting.substr(start, end - start)) == 0) return "";
    if (end == std::string::npos) break;
    start = end + 2;
  }
  return " (all on host '" + placement.hosts[1].name +
         "': nothing of theirs reached the launcher's host over the "
         "link; multicast must cross it, with ttl >= 1 and a 224.0.0.0/4 route on each end)";
}

}  // namespace nimble::launcher
