#pragma once
/// Where each process of a run runs: the scenario's `hosts` section.
///
/// A lab may split the rig over two machines, e.g. the controller and the estimator on the
/// flight computer, the plant and the motion capture on the simulation PC:
///
///     hosts:
///       sim: [plant, mocap]                  # the first host is the launcher's: it records and watches
///       flight:                              # a mapping gives the host's end of the link as well
///         processes: [controller, estimator]
///         address: 10.76.67.2/30
///
/// Every listed process must be one of the scenario's `processes`, none on two hosts; processes
/// not placed run on the first host. With two hosts `rig run` flies the rig across two network
/// namespaces joined by a veth pair (netns.h, HostLink) on an LCM URL with ttl=1, as over a lab
/// network. Both sides of the CAN bridge must run on the first host: the run's virtual CAN
/// interface lives in that host's network namespace, and a vcan cannot span two.
///
/// On two real machines the second host says `start: by_hand`: its processes are external
/// (run.external_processes): `rig run` does not start them but prints the command of each, to be
/// run on that machine (by hand or over ssh) with the resolved scenario and the run's LCM URL,
/// waits for their READY and flies them as any other process. That needs the lab network's URL (run.lcm_url with ttl >= 1,
/// run.network_namespace: never) and the lockstep clock: a real-time start time is the
/// launcher's CLOCK_MONOTONIC, which another machine does not share.

#include <memory>
#include <string>
#include <vector>

#include "scenario/scenario.h"

namespace nimble::launcher {

struct LaunchConfig;  // run_plan.h
class HostLink;       // netns.h
struct HostSummary;   // run_report.h

/// At most two hosts: the emulated link is one veth pair, a point-to-point cable between the
/// launcher's host and one other. (A third host would need a bridge that forwards multicast.)
constexpr std::size_t kMaxHosts = 2;

/// The addresses of the two ends of the emulated link when the scenario gives none: a /30 of
/// the private 10/8 range (10.76.67 after the rig's multicast group 239.255.76.67). They exist
/// only inside the run's own network namespaces, so they cannot clash with the lab's network.
constexpr const char* kDefaultHostAddresses[kMaxHosts] = {"10.76.67.1/30", "10.76.67.2/30"};

/// The LCM URL of a run over two hosts: as kNamespaceLcmUrl, with ttl=1 so that the multicast
/// datagrams leave the host (ttl=0 keeps them on it) but are not routed beyond the link.
constexpr const char* kTwoHostLcmUrl = "udpm://239.255.76.67:7667?ttl=1&recv_buf_size=8388608";

/// One host of the run.
struct HostConfig {
  std::string name;                    ///< as written in the scenario, e.g. "sim"
  std::vector<std::string> processes;  ///< in the order of the scenario's `processes`
  std::string address;                 ///< its end of the emulated link, IPv4 with prefix, e.g. 10.76.67.1/30
  /// The host's processes are started on it by hand (a real machine), not by the launcher.
  bool by_hand = false;
};

/// The placement of a run's processes.
struct HostPlacement {
  /// hosts[0] is the launcher's. Empty: the scenario has no hosts section (all on this host).
  std::vector<HostConfig> hosts;

  /// True if the run spans more than one host.
  bool split() const { return hosts.size() > 1; }
  /// True if the second host is emulated: a network namespace the launcher makes, and starts
  /// that host's processes in.
  bool emulated() const { return split() && !hosts[1].by_hand; }
  /// True if `process` runs on a host whose processes are started by hand.
  bool started_by_hand(const std::string& process) const { return split() && hosts[host_index(process)].by_hand; }
  /// Index into `hosts` of the host that runs `process` (0 without a hosts section).
  std::size_t host_index(const std::string& process) const;
};

/// Reads and validates the `hosts` section of `scenario` (processes already resolved, CAN
/// bridge sides included) against the launcher's settings `launch`.
/// @throws ConfigError naming the key (hosts, hosts.<host>, hosts.<host>.address, ...) and
/// what is wrong.
HostPlacement host_placement_from(const Scenario& scenario, const LaunchConfig& launch);

/// With two hosts: creates the second host (HostLink) from the launcher's private network
/// namespace, the ends of the link at the hosts' addresses. Returns nullptr with `problem` set
/// if the launcher is not in a private namespace (`in_private_namespace` false) or a step fails.
std::unique_ptr<HostLink> link_hosts(const HostPlacement& placement, bool in_private_namespace, std::string* problem);

/// Adds the processes of a host started by hand to `external` (run.external_processes: the
/// launcher does not start them, prints the command of each and waits for their READY), each once.
void add_by_hand_processes(const HostPlacement& placement, std::vector<std::string>& external);

/// What the run report says of the hosts: each with its processes, the launcher's host with
/// the launcher's namespace, the second with `link`'s (may be null). Empty without a hosts
/// section.
std::vector<HostSummary> host_summaries(const HostPlacement& placement, const HostLink* link);

/// For an error about processes that never reported (`waiting`, names separated by ", "): when
/// all of them run on the second host, a note that nothing of theirs crossed the link; else "".
std::string hosts_hint(const HostPlacement& placement, const std::string& waiting);

/// Parses "a.b.c.d/n" (n in [1, 30]); false if it is not one.
bool parse_ipv4_prefix(const std::string& text, unsigned* address, int* prefix);

}  // namespace nimble::launcher
