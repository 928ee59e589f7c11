// bench_can_bridge: the latency the CAN actuator link adds, through the real bridge processes.
//
//   bench_can_bridge [--count N] [--rate HZ] [--warmup N] [--bridge PATH] [--scenario FILE]
//                    [--candump FILE]
//
// Needs SocketCAN: on a kernel without CAN run it as
//   tools/canvm/canvm run -- build/bin/bench_can_bridge
//
// Set-up, as `rig run` does it for `actuator_link: can`:
//  - the bench moves itself into a private network namespace (loopback with multicast) before it
//    starts any thread, and creates vcan0 there; the bridges it starts inherit both;
//  - it writes a resolved scenario (the base scenario, default rig_configs/hover.yaml, with
//    actuator_link: can and no candump log unless --candump) to a temporary directory;
//  - it starts nimble_can_bridge (found next to this executable) as can_flight and can_rig on a
//    udpm URL, waits for both HEARTBEAT READY, sends RUN_CONTROL COMMAND_START (real time),
//    waits for HEARTBEAT RUNNING.
//
// Method. The main thread publishes actuator_command_t on ACTUATOR_CMD at a fixed rate (512 Hz by
// default, the controller's rate; absolute deadlines on CLOCK_MONOTONIC), each command with its
// own seq and the next rolling counter, and stores CLOCK_MONOTONIC just before lcm publish().
// A second LCM instance, used only by a receiving thread that blocks in handleTimeout(), is
// subscribed to two channels and stores CLOCK_MONOTONIC on entry to the handler, before decoding:
//  - ACTUATOR_CMD itself: the direct LCM hop (the same datagram can_flight receives), i.e. what
//    the plant would see over `actuator_link: lcm`;
//  - ACTUATOR_CMD_CAN: the same command after can_flight -> 2 frames on vcan0 -> can_rig ->
//    LCM, i.e. what the plant sees over `actuator_link: can` (seq survives the link).
// Both samples of one command come from the same publish and are received by the same thread
// through the same LCM code, so the bench's own publish and receive costs are in both; the
// difference is what the CAN link adds: one more LCM hop, two bridge wake-ups, encoding and
// decoding, and the kernel's CAN path. The publisher never handles messages and the receiver
// never publishes, so neither waits for the other. The first --warmup commands are not counted.
// Each command is checked field by field against what was sent.
//
// At the end the bench sends RUN_CONTROL COMMAND_STOP (SIGTERM, then SIGKILL, if a bridge does
// not exit), reaps the bridges and prints each one's last CAN_HEALTH (published at exit).

#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <lcm/lcm-cpp.hpp>
#include <nimble/actuator_command_t.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/heartbeat_t.hpp>
#include <nimble/run_control_t.hpp>

#include "bench/can_bridge_commands.h"
#include "cmdline/args.h"
#include "contract/channels.h"
#include "contract/default_rates.h"
#include "launcher/netns.h"
#include "launcher/supervisor.h"
#include "scenario/scenario.h"

namespace {

namespace fs = std::filesystem;
using nimble::actuator_command_t;
using nimble::can_health_t;
using nimble::fault_event_t;
using nimble::heartbeat_t;
using nimble::run_control_t;
using nimble::bench::make_command;
using nimble::bench::same_values;

const std::string& kCmd = nimble::contract::channels::kActuatorCommand;
const std::string& kCmdCan = nimble::contract::channels::kActuatorCommandCan;
const char* const kUrl = "udpm://239.255.76.67:7667?ttl=0&recv_buf_size=8388608";
const char* const kInterface = "vcan0";

int64_t monotonic_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

int64_t wall_us() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000 + ts.tv_nsec / 1000;
}

void sleep_ms(int ms) { std::this_thread::sleep_for(std::chrono::milliseconds(ms)); }

// ---- statistics -------------------------------------------------------------------------------

struct Summary {
  double p50_us = 0, p99_us = 0, max_us = 0;
  std::size_t n = 0;
};

Summary summarise(std::vector<int64_t> ns) {
  Summary s;
  if (ns.empty()) return s;
  std::sort(ns.begin(), ns.end());
  auto at = [&](double q) {
    const std::size_t i =
        std::min(ns.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ns.size() - 1) + 0.5));
    return static_cast<double>(ns[i]) / 1000.0;
  };
  s.p50_us = at(0.50);
  s.p99_us = at(0.99);
  s.max_us = static_cast<double>(ns.back()) / 1000.0;
  s.n = ns.size();
  return s;
}

void print(const char* what, const Summary& s) {
  if (s.n == 0) {
    std::printf("  %-46s no samples\n", what);
    return;
  }
  std::printf("  %-46s p50 %8.1f us   p99 %8.1f us   max %8.1f us   (n = %zu)\n", what, s.p50_us, s.p99_us, s.max_us,
              s.n);
}

// ---- the receiving side -----------------------------------------------------------------------

struct HeartbeatSeen {
  int32_t pid = 0;
  int8_t state = -1;
};

class Receiver {
 public:
  explicit Receiver(int64_t total) : direct_rx_(total, -1), can_rx_(total, -1) {}

  /// Subscribes on `lcm`; call before the thread starts.
  void subscribe(lcm::LCM& lcm) {
    lcm.subscribe(kCmd, &Receiver::on_direct, this)->setQueueCapacity(100000);
    lcm.subscribe(kCmdCan, &Receiver::on_can, this)->setQueueCapacity(100000);
    lcm.subscribe(nimble::contract::channels::kHeartbeat, &Receiver::on_heartbeat, this)->setQueueCapacity(1000);
    lcm.subscribe(nimble::contract::channels::kCanHealth, &Receiver::on_health, this)->setQueueCapacity(1000);
    lcm.subscribe(nimble::contract::channels::kFault, &Receiver::on_fault, this)->setQueueCapacity(1000);
  }

  std::vector<int64_t> direct_rx_, can_rx_;  // receive time by seq [ns, CLOCK_MONOTONIC]; -1 = none
  std::atomic<int64_t> direct_count{0}, can_count{0};
  // Written by the receiving thread only; read after it has been joined.
  int64_t direct_other = 0, can_other = 0, can_duplicates = 0, can_mismatches = 0, malformed = 0;
  std::string can_sources;

  std::mutex mu;  // guards what follows
  std::map<std::string, HeartbeatSeen> heartbeats;
  std::map<std::string, can_health_t> health;
  std::vector<std::string> faults;
  int64_t fault_count = 0;

 private:
  void on_direct(const lcm::ReceiveBuffer* rb, const std::string&) {
    const int64_t t = monotonic_ns();
    actuator_command_t c;
    if (c.decode(rb->data, 0, rb->data_size) != static_cast<int>(rb->data_size)) {
      ++malformed;
      return;
    }
    if (c.seq < 0 || c.seq >= static_cast<int64_t>(direct_rx_.size()) || direct_rx_[c.seq] >= 0) {
      ++direct_other;
      return;
    }
    direct_rx_[c.seq] = t;
    direct_count.fetch_add(1, std::memory_order_release);
  }

  void on_can(const lcm::ReceiveBuffer* rb, const std::string&) {
    const int64_t t = monotonic_ns();
    actuator_command_t c;
    if (c.decode(rb->data, 0, rb->data_size) != static_cast<int>(rb->data_size)) {
      ++malformed;
      return;
    }
    if (c.seq < 0 || c.seq >= static_cast<int64_t>(can_rx_.size())) {
      ++can_other;
      return;
    }
    if (can_rx_[c.seq] >= 0) {
      ++can_duplicates;
      return;
    }
    can_rx_[c.seq] = t;
    if (!same_values(c, make_command(c.seq))) ++can_mismatches;
    if (can_sources.find(c.source) == std::string::npos) can_sources += (can_sources.empty() ? "" : ", ") + c.source;
    can_count.fetch_add(1, std::memory_order_release);
  }

  void on_heartbeat(const lcm::ReceiveBuffer* rb, const std::string&) {
    heartbeat_t hb;
    if (hb.decode(rb->data, 0, rb->data_size) != static_cast<int>(rb->data_size)) return;
    std::lock_guard<std::mutex> lock(mu);
    heartbeats[hb.process] = HeartbeatSeen{hb.pid, hb.state};
  }

  void on_health(const lcm::ReceiveBuffer* rb, const std::string&) {
    can_health_t h;
    if (h.decode(rb->data, 0, rb->data_size) != static_cast<int>(rb->data_size)) return;
    std::lock_guard<std::mutex> lock(mu);
    auto it = health.find(h.process);
    if (it == health.end() || h.seq >= it->second.seq) health[h.process] = h;
  }

  void on_fault(const lcm::ReceiveBuffer* rb, const std::string&) {
    fault_event_t f;
    if (f.decode(rb->data, 0, rb->data_size) != static_cast<int>(rb->data_size)) return;
    std::lock_guard<std::mutex> lock(mu);
    ++fault_count;
    if (faults.size() < 8) faults.push_back(f.process + ": " + f.message);
  }
};

// ---- the bridge processes ---------------------------------------------------------------------

using nimble::launcher::ChildProcess;
using nimble::launcher::ProcessSupervisor;

void publish_run_control(lcm::LCM& lcm, int64_t* seq, int8_t command, int64_t duration_ns) {
  run_control_t rc{};
  rc.utime = wall_us();
  rc.seq = (*seq)++;
  rc.command = command;
  rc.clock_mode = run_control_t::CLOCK_MODE_REALTIME;
  rc.t0_monotonic_ns = command == run_control_t::COMMAND_START ? monotonic_ns() : 0;
  rc.duration_ns = duration_ns;
  rc.run_id = "bench_can_bridge-" + std::to_string(getpid());
  rc.num_participants = 0;  // real time: no lockstep participants
  lcm.publish(nimble::contract::channels::kRunControl, &rc);
}

/// Waits until every child has announced `state` on HEARTBEAT (under its own pid). Returns ""
/// or what went wrong.
std::string wait_for_state(Receiver& rx, ProcessSupervisor& supervisor, int8_t state, int timeout_ms,
                           const std::function<void()>& every_second = {}) {
  const std::vector<ChildProcess>& children = supervisor.children();
  const int64_t start = monotonic_ns();
  int64_t next_second = start + 1000000000;
  for (;;) {
    bool all = true;
    {
      std::lock_guard<std::mutex> lock(rx.mu);
      for (const auto& c : children) {
        auto it = rx.heartbeats.find(c.name);
        all = all && it != rx.heartbeats.end() && it->second.pid == c.pid && it->second.state == state;
      }
    }
    if (all) return "";
    if (const ChildProcess* dead = supervisor.reap()) {
      return dead->name + " ended before the run started (" + dead->describe() + ")";
    }
    const int64_t now = monotonic_ns();
    if (now - start > static_cast<int64_t>(timeout_ms) * 1000000) {
      return "no HEARTBEAT state " + std::to_string(state) + " from every bridge within " + std::to_string(timeout_ms) +
             " ms";
    }
    if (every_second && now >= next_second) {
      every_second();
      next_second += 1000000000;
    }
    sleep_ms(5);
  }
}

std::string self_dir() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

std::string where_measured() {
  const long cpus = sysconf(_SC_NPROCESSORS_ONLN);
  std::string load = "?";
  std::ifstream la("/proc/loadavg");
  if (la) {
    std::string a, b, c;
    la >> a >> b >> c;
    load = a + " " + b + " " + c;
  }
  const char* guest = std::getenv("CANVM_GUEST");
  if (guest != nullptr && std::string(guest) == "1") {
    return "inside the canvm VM (qemu software emulation, " + std::to_string(cpus) +
           " emulated CPU(s); guest load average " + load + ")";
  }
  return "host kernel with vcan (" + std::to_string(cpus) + " CPUs, load average " + load + ")";
}

struct Options {
  int count = 5000;
  int warmup = 200;
  double rate_hz = nimble::contract::kDefaultControlRateHz;
  std::string bridge;
  std::string scenario = std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml";
  std::string candump;  ///< can_rig's candump log of every frame it received; empty: none
};

/// A private network namespace with multicast loopback, and vcan0 in it (before any thread);
/// false, with the reason on stderr, where this machine cannot.
bool open_network(nimble::launcher::NamespaceResult& ns) {
  ns = nimble::launcher::enter_private_network_namespace();
  if (!ns.ok) {
    std::fprintf(stderr,
                 "bench_can_bridge: cannot create a private network namespace: %s\n"
                 "  (needs root or unprivileged user namespaces; on a kernel without CAN run it as\n"
                 "   tools/canvm/canvm run -- build/bin/bench_can_bridge)\n",
                 ns.detail.c_str());
    return false;
  }
  const std::string can_problem = nimble::launcher::ensure_can_interface(kInterface, true);
  if (!can_problem.empty()) {
    std::fprintf(stderr,
                 "bench_can_bridge: no CAN interface %s: %s\n"
                 "  run the bench through the CAN VM instead: tools/canvm/canvm run -- build/bin/bench_can_bridge\n",
                 kInterface, can_problem.c_str());
    return false;
  }
  return true;
}

/// The scenario the bridges read: the bench's, over the CAN link on vcan0, with or without a
/// candump log. False, with the reason on stderr, if it cannot be written.
bool write_scenario(const Options& opt, const std::string& scenario_file) {
  std::vector<nimble::Override> overrides{{"actuator_link", "can"}, {"can_bridge.interface", kInterface}};
  if (opt.candump.empty()) {
    overrides.push_back({"can_bridge.candump_log", "false"});
  } else {
    overrides.push_back({"can_bridge.candump_log", "true"});
    std::string quoted = "'";  // a YAML single-quoted string
    for (const char c : fs::absolute(opt.candump).string()) quoted += c == '\'' ? std::string("''") : std::string(1, c);
    overrides.push_back({"can_bridge.candump_file", quoted + "'"});
  }
  const nimble::Scenario s = nimble::load_scenario(opt.scenario, overrides);
  std::ofstream out(scenario_file);
  out << "# Resolved scenario for bench_can_bridge (from " << opt.scenario << ")\n" << nimble::to_yaml(s.root);
  if (!out) {
    std::fprintf(stderr, "bench_can_bridge: cannot write %s\n", scenario_file.c_str());
    return false;
  }
  return true;
}

/// Each bridge's last CAN_HEALTH, and the FAULT events the run saw.
void print_health(Receiver& rx, const std::vector<ChildProcess>& children) {
  std::lock_guard<std::mutex> lock(rx.mu);
  for (const auto& c : children) {
    auto it = rx.health.find(c.name);
    if (it == rx.health.end()) {
      std::printf("  CAN_HEALTH %-10s none received\n", c.name.c_str());
      continue;
    }
    const can_health_t& h = it->second;
    std::printf(
        "  CAN_HEALTH %-10s (seq %lld) to CAN %lld, to LCM %lld, frames sent %lld, received %lld; rejected: "
        "unknown id %lld, wrong length %lld, bad checksum %lld, stale counter %lld, out of range %lld; "
        "counter gaps %lld, ENOBUFS %lld, send retries %lld, send dropped %lld, receive dropped %lld, error frames "
        "%lld\n",
        c.name.c_str(), static_cast<long long>(h.seq), static_cast<long long>(h.messages_to_can),
        static_cast<long long>(h.messages_to_lcm), static_cast<long long>(h.frames_sent),
        static_cast<long long>(h.frames_received), static_cast<long long>(h.rejected_unknown_id),
        static_cast<long long>(h.rejected_wrong_length), static_cast<long long>(h.rejected_bad_checksum),
        static_cast<long long>(h.rejected_stale_counter), static_cast<long long>(h.rejected_out_of_range),
        static_cast<long long>(h.counter_gaps), static_cast<long long>(h.send_enobufs),
        static_cast<long long>(h.send_retries), static_cast<long long>(h.send_dropped),
        static_cast<long long>(h.receive_dropped), static_cast<long long>(h.error_frames));
  }
  if (rx.fault_count > 0) {
    std::printf("  FAULT events: %lld, e.g.\n", static_cast<long long>(rx.fault_count));
    for (const auto& f : rx.faults) std::printf("    %s\n", f.c_str());
  }
}

/// The latencies of the direct hop and of the CAN path per command, what was lost, and the
/// bridges' health. Returns 0 if any command crossed the CAN path, else 1.
int report(const Options& opt, Receiver& rx, const std::vector<int64_t>& sent, int64_t late,
           const std::string& ns_detail, const std::string& bridge, const std::string& stop_how,
           const std::vector<ChildProcess>& children) {
  std::vector<int64_t> direct_ns, can_ns, added_ns;
  int64_t direct_lost = 0, can_lost = 0, warm_direct = 0, warm_can = 0;
  const int64_t total = static_cast<int64_t>(sent.size());
  for (int64_t seq = 0; seq < total; ++seq) {
    const int64_t d = rx.direct_rx_[seq], k = rx.can_rx_[seq];
    if (seq < opt.warmup) {
      warm_direct += d >= 0;
      warm_can += k >= 0;
      continue;
    }
    if (d >= 0)
      direct_ns.push_back(d - sent[seq]);
    else
      ++direct_lost;
    if (k >= 0)
      can_ns.push_back(k - sent[seq]);
    else
      ++can_lost;
    if (d >= 0 && k >= 0) added_ns.push_back(k - d);
  }
  const Summary direct = summarise(direct_ns), can = summarise(can_ns), added = summarise(added_ns);

  std::printf("bench_can_bridge: %d commands at %g Hz after %d warm-up, %s on %s\n", opt.count, opt.rate_hz, opt.warmup,
              kUrl, kInterface);
  std::printf("  measured %s\n", where_measured().c_str());
  std::printf("  network: %s\n", ns_detail.c_str());
  std::printf("  bridge: %s (scenario %s)\n", bridge.c_str(), opt.scenario.c_str());
  print("direct LCM hop (ACTUATOR_CMD)", direct);
  print("LCM -> can_flight -> vcan0 -> can_rig -> LCM", can);
  if (direct.n > 0 && can.n > 0) {
    std::printf("  %-46s %8.1f us (difference of the medians)\n", "added by the CAN path", can.p50_us - direct.p50_us);
  }
  print("  per command, CAN path minus direct hop", added);
  std::printf(
      "  lost (published, not received): direct %lld of %d, CAN path %lld of %d; warm-up received: direct "
      "%lld, CAN %lld of %d\n",
      static_cast<long long>(direct_lost), opt.count, static_cast<long long>(can_lost), opt.count,
      static_cast<long long>(warm_direct), static_cast<long long>(warm_can), opt.warmup);
  std::printf(
      "  CAN path: values differing from those sent %lld, duplicates %lld, unknown seq %lld, source '%s'; "
      "undecodable messages %lld; publisher late by > 1 period %lld times\n",
      static_cast<long long>(rx.can_mismatches), static_cast<long long>(rx.can_duplicates),
      static_cast<long long>(rx.can_other), rx.can_sources.c_str(), static_cast<long long>(rx.malformed),
      static_cast<long long>(late));
  std::printf("  bridges stopped by %s: ", stop_how.c_str());
  for (std::size_t i = 0; i < children.size(); ++i) {
    std::printf("%s%s %s", i ? ", " : "", children[i].name.c_str(), children[i].describe().c_str());
  }
  std::printf("\n");
  print_health(rx, children);
  return can.n > 0 ? 0 : 1;
}

/// Both bridges on CPU 0, as `rig run` places the rig's processes (run.rig_cpus): vcan hands a
/// frame to the receive path of the CPU that sent it, so a sender that migrates between CPUs
/// can have its frames delivered out of order, which the counter check then drops as stale.
void start_bridges(ProcessSupervisor& supervisor, const std::string& bridge, const std::string& scenario_file) {
  cpu_set_t all_cpus, cpu0;
  const bool pinned = sched_getaffinity(0, sizeof all_cpus, &all_cpus) == 0;
  CPU_ZERO(&cpu0);
  CPU_SET(0, &cpu0);
  if (pinned) sched_setaffinity(0, sizeof cpu0, &cpu0);
  for (const std::string name : {"can_flight", "can_rig"}) {
    supervisor.start(name, bridge, {"--name", name, "--scenario", scenario_file, "--lcm-url", kUrl});
  }
  if (pinned) sched_setaffinity(0, sizeof all_cpus, &all_cpus);
}

/// Publishes the commands at `period_ns` on absolute deadlines; returns each one's publish time.
/// `late` counts the times the publisher fell behind by more than a period.
std::vector<int64_t> publish_commands(lcm::LCM& pub, int64_t total, int64_t period_ns, int64_t& late) {
  std::vector<int64_t> sent(total, -1);
  int64_t deadline = monotonic_ns() + period_ns;
  for (int64_t seq = 0; seq < total; ++seq) {
    timespec ts{static_cast<time_t>(deadline / 1000000000), static_cast<long>(deadline % 1000000000)};
    while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
    }
    actuator_command_t c = make_command(seq);
    const int64_t t = monotonic_ns();
    c.utime = t / 1000;
    sent[seq] = t;
    pub.publish(kCmd, &c);
    deadline += period_ns;
    // Behind by more than a period (a stalled publisher): skip ahead instead of bursting.
    const int64_t now = monotonic_ns();
    if (now > deadline + period_ns) {
      ++late;
      deadline = now + period_ns;
    }
  }
  return sent;
}

/// Waits until every command has come in both ways, or for 3 s of silence.
void wait_for_commands(Receiver& rx, int64_t total) {
  int64_t last_progress = monotonic_ns();
  int64_t last_seen = -1;
  while (rx.direct_count.load(std::memory_order_acquire) < total ||
         rx.can_count.load(std::memory_order_acquire) < total) {
    const int64_t seen = rx.direct_count.load() + rx.can_count.load();
    if (seen != last_seen) {
      last_seen = seen;
      last_progress = monotonic_ns();
    } else if (monotonic_ns() - last_progress > 3000000000LL) {
      break;
    }
    sleep_ms(10);
  }
}

/// Stops the bridges with RUN_CONTROL COMMAND_STOP (then signals) and reaps them; returns how.
std::string stop_bridges(lcm::LCM& pub, int64_t& rc_seq, ProcessSupervisor& supervisor) {
  publish_run_control(pub, &rc_seq, run_control_t::COMMAND_STOP, 0);
  bool exited = supervisor.wait_all(2.0);
  if (!exited) {
    publish_run_control(pub, &rc_seq, run_control_t::COMMAND_STOP, 0);
    exited = supervisor.wait_all(3.0);
  }
  std::string stop_how = "RUN_CONTROL COMMAND_STOP";
  if (!exited) {
    stop_how += ", then SIGTERM (then SIGKILL if needed)";
    supervisor.stop(0.0);
  }
  return stop_how;
}

int run(const Options& opt) {
  // 1. Private network namespace with multicast loopback, and vcan0 in it (before any thread).
  nimble::launcher::NamespaceResult ns;
  if (!open_network(ns)) return 1;

  // 2. The resolved scenario the bridges read.
  const std::string bridge = opt.bridge.empty() ? self_dir() + "/nimble_can_bridge" : opt.bridge;
  if (access(bridge.c_str(), X_OK) != 0) {
    std::fprintf(stderr, "bench_can_bridge: %s is not an executable (build the nimble_can_bridge target)\n",
                 bridge.c_str());
    return 1;
  }
  char tmpl[] = "/tmp/bench_can_bridge.XXXXXX";
  if (mkdtemp(tmpl) == nullptr) {
    std::fprintf(stderr, "bench_can_bridge: mkdtemp: %s\n", std::strerror(errno));
    return 1;
  }
  const std::string dir = tmpl;
  struct RemoveDir {
    std::string d;
    ~RemoveDir() {
      std::error_code ec;
      fs::remove_all(d, ec);
    }
  } remove_dir{dir};
  const std::string scenario_file = dir + "/scenario.yaml";
  if (!write_scenario(opt, scenario_file)) return 1;

  nimble::load_scenario(scenario_file);  // what the bridges will load: fail here if it does not

  // 3. LCM: one instance to publish (never subscribed), one for the receiving thread.
  lcm::LCM pub(kUrl);
  lcm::LCM sub(kUrl);
  if (!pub.good() || !sub.good()) {
    std::fprintf(stderr, "bench_can_bridge: LCM does not start on %s\n", kUrl);
    return 1;
  }
  const int64_t total = static_cast<int64_t>(opt.warmup) + opt.count;
  Receiver rx(total);
  rx.subscribe(sub);
  std::atomic<bool> stop_rx{false};
  std::thread rx_thread([&] {
    while (!stop_rx.load(std::memory_order_relaxed)) sub.handleTimeout(50);
  });
  struct JoinRx {
    std::atomic<bool>& stop;
    std::thread& t;
    ~JoinRx() {
      stop = true;
      if (t.joinable()) t.join();
    }
  } join_rx{stop_rx, rx_thread};

  ProcessSupervisor supervisor;
  start_bridges(supervisor, bridge, scenario_file);
  const std::vector<ChildProcess>& children = supervisor.children();
  auto abort_run = [&](const std::string& why) {
    std::fprintf(stderr, "bench_can_bridge: %s\n", why.c_str());
    supervisor.stop(0.0);
    for (const auto& c : children) std::fprintf(stderr, "  %s: %s\n", c.name.c_str(), c.describe().c_str());
    return 1;
  };

  std::string problem = wait_for_state(rx, supervisor, heartbeat_t::STATE_READY, 60000);
  if (!problem.empty()) return abort_run(problem);
  const int64_t period_ns = static_cast<int64_t>(std::llround(1e9 / opt.rate_hz));
  // Long enough that the bridges are still in their run when the last command goes out (they
  // keep bridging afterwards too, until COMMAND_STOP).
  const int64_t duration_ns = total * period_ns * 4 + 120LL * 1000000000;
  int64_t rc_seq = 0;
  publish_run_control(pub, &rc_seq, run_control_t::COMMAND_START, duration_ns);
  problem = wait_for_state(rx, supervisor, heartbeat_t::STATE_RUNNING, 10000, [&] {
    publish_run_control(pub, &rc_seq, run_control_t::COMMAND_START, duration_ns);  // in case it was lost
  });
  if (!problem.empty()) return abort_run(problem);
  sleep_ms(300);  // let the start-up messages settle

  // 4. The commands.
  int64_t late = 0;
  const std::vector<int64_t> sent = publish_commands(pub, total, period_ns, late);
  // Everything in, or 3 s of silence.
  wait_for_commands(rx, total);

  // 5. Stop the bridges, reap them; their last CAN_HEALTH goes out as they exit.
  const std::string stop_how = stop_bridges(pub, rc_seq, supervisor);
  sleep_ms(300);  // the final CAN_HEALTH through the receiving thread
  stop_rx = true;
  rx_thread.join();

  // 6. Report.
  return report(opt, rx, sent, late, ns.detail, bridge, stop_how, children);
}

}  // namespace

int main(int argc, char** argv) {
  Options opt;
  nimble::cmdline::CommandLine cl(
      "bench_can_bridge",
      "The latency the CAN actuator link adds, through the real bridge processes: commands published on\n"
      "ACTUATOR_CMD at a fixed rate, received directly and after can_flight -> vcan0 -> can_rig, in a\n"
      "private network namespace of its own.");
  cl->footer("Needs SocketCAN; on a kernel without CAN: tools/canvm/canvm run -- build/bin/bench_can_bridge");
  cl->add_option("--count", opt.count, "commands measured")
      ->check(CLI::Range(1, 10000000))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--rate", opt.rate_hz, "publish rate (the controller's)")
      ->check(nimble::cmdline::kFinite & CLI::Range(1e-3, 1e5))
      ->type_name("HZ")
      ->capture_default_str();
  cl->add_option("--warmup", opt.warmup, "commands sent first and not counted")
      ->check(CLI::Range(0, 10000000))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--bridge", opt.bridge, "nimble_can_bridge (default: next to this executable)")->type_name("PATH");
  cl->add_option("--scenario", opt.scenario, "base scenario (default rig_configs/hover.yaml)")->type_name("FILE");
  cl->add_option("--candump", opt.candump,
                 "can_rig writes every frame it receives there (candump -L format; the logging adds to "
                 "can_rig's work)")
      ->type_name("FILE");
  if (const auto done = cl.parse(argc, argv)) return *done;
  if (static_cast<int64_t>(opt.count) + opt.warmup > 10000000) return cl.fail("--count + --warmup must be <= 10000000");
  try {
    return run(opt);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_can_bridge: %s\n", e.what());
    return 1;
  }
}
