#include "bench/bench_floor.h"

#include <poll.h>
#include <sched.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <cstring>
#include <functional>
#include <map>
#include <stdexcept>

#include <memory>

#include "transport/bus.h"
#include "transport/clock.h"

namespace nimble::launcher::bench {
namespace {

using transport::monotonic_ns;

// Channels of the floors: their own names, so that a floor never mixes with a rig run.
constexpr const char* kStop = "FLOOR_STOP";
constexpr const char* kTick = "FLOOR_TICK";
constexpr const char* kAck = "FLOOR_ACK";
std::string hop_channel(int i) { return "FLOOR_HOP" + std::to_string(i); }

/// Applies `s` to the calling process; returns "" or what failed.
std::string apply(const FloorSettings& s, int default_priority = 0) {
  const int priority = s.priority > 0 ? s.priority : default_priority;
  if (!s.cpus.empty()) {
    cpu_set_t set;
    CPU_ZERO(&set);
    for (int c : s.cpus) {
      if (c >= 0 && c < CPU_SETSIZE) CPU_SET(c, &set);
    }
    if (::sched_setaffinity(0, sizeof set, &set) != 0) return std::string("sched_setaffinity: ") + std::strerror(errno);
  }
  if (priority > 0) {
    sched_param sp{};
    sp.sched_priority = priority;
    if (::sched_setscheduler(0, SCHED_FIFO, &sp) != 0) {
      return "SCHED_FIFO " + std::to_string(priority) + ": " + std::strerror(errno);
    }
  }
  return "";
}

void sleep_until(int64_t t_ns) {
  timespec ts{static_cast<time_t>(t_ns / 1000000000LL), static_cast<long>(t_ns % 1000000000LL)};
  while (::clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr) == EINTR) {
  }
}

/// Handles messages until `deadline_ns` (CLOCK_MONOTONIC), sleeping in ppoll between them.
void handle_until(transport::Bus& bus, int64_t deadline_ns) {
  const int fd = bus.fileno();
  for (;;) {
    const int64_t left = deadline_ns - monotonic_ns();
    if (left <= 0) return;
    pollfd pfd{fd, POLLIN, 0};
    timespec ts{static_cast<time_t>(left / 1000000000LL), static_cast<long>(left % 1000000000LL)};
    if (::ppoll(&pfd, 1, &ts, nullptr) > 0 && (pfd.revents & POLLIN)) bus.drain();
  }
}

/// What a child sends back through its pipe.
struct ChildResult {
  int ok = 0;
  char error[200] = {};
  double values[8] = {};
};

/// Runs `body` in a child process; the child writes its ChildResult to a pipe.
pid_t spawn(const std::function<ChildResult()>& body, int* read_fd) {
  int fds[2];
  if (::pipe(fds) != 0) throw std::runtime_error(std::string("pipe: ") + std::strerror(errno));
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("fork: ") + std::strerror(errno));
  if (pid == 0) {
    ::close(fds[0]);
    ChildResult r;
    try {
      r = body();
    } catch (const std::exception& e) {
      r.ok = 0;
      std::snprintf(r.error, sizeof r.error, "%s", e.what());
    }
    if (::write(fds[1], &r, sizeof r) != static_cast<ssize_t>(sizeof r)) ::_exit(3);
    ::_exit(r.ok ? 0 : 1);
  }
  ::close(fds[1]);
  *read_fd = fds[0];
  return pid;
}

/// Waits for a child spawned with spawn() and returns its result.
ChildResult collect(pid_t pid, int read_fd, const std::string& what) {
  ChildResult r;
  const ssize_t n = ::read(read_fd, &r, sizeof r);
  ::close(read_fd);
  int status = 0;
  ::waitpid(pid, &status, 0);
  if (n != static_cast<ssize_t>(sizeof r)) throw std::runtime_error(what + ": the process died without a result");
  if (!r.ok) throw std::runtime_error(what + ": " + r.error);
  return r;
}

/// Collects the lead process's result, then its helpers' (killed at once if the lead failed,
/// since they would wait for a stop that never comes). Throws the first error.
ChildResult collect_group(pid_t lead, int lead_fd, const std::string& lead_what,
                          const std::vector<std::pair<pid_t, int>>& helpers, const std::string& helper_what) {
  ChildResult r;
  std::string error;
  try {
    r = collect(lead, lead_fd, lead_what);
  } catch (const std::exception& e) {
    error = e.what();
  }
  for (const auto& [pid, fd] : helpers) {
    if (!error.empty()) ::kill(pid, SIGKILL);
    try {
      collect(pid, fd, helper_what);
    } catch (const std::exception& e) {
      if (error.empty()) error = e.what();
    }
  }
  if (!error.empty()) throw std::runtime_error(error);
  return r;
}

ChildResult fail(const std::string& message) {
  ChildResult r;
  std::snprintf(r.error, sizeof r.error, "%s", message.c_str());
  return r;
}

ChildResult from_percentiles(std::vector<int64_t>& samples) {
  const Percentiles p = percentiles(samples);
  ChildResult r;
  r.ok = 1;
  r.values[0] = p.p50_us;
  r.values[1] = p.p99_us;
  r.values[2] = p.max_us;
  r.values[3] = static_cast<double>(p.count);
  return r;
}

Percentiles to_percentiles(const ChildResult& r) {
  return Percentiles{r.values[0], r.values[1], r.values[2], static_cast<int64_t>(r.values[3])};
}

/// The rig's own transport (transport::Bus: LCM's wire format and its publish, received as the
/// rig's processes receive), so that a floor costs what the rig's hops cost without the rig.
std::unique_ptr<transport::Bus> open_bus(const std::string& url) { return std::make_unique<transport::Bus>(url); }

/// `handler` for the raw bytes of `channel`.
void on(transport::Bus& bus, const std::string& channel, std::function<void(const void*, int)> handler) {
  bus.subscribe_raw(
      channel, [h = std::move(handler)](const std::string&, const void* data, int size, int64_t) { h(data, size); });
}

/// A helper process's life once subscribed: handle messages until FLOOR_STOP (or `guard_s`).
ChildResult serve(transport::Bus& bus, double guard_s) {
  bool stop = false;
  on(bus, kStop, [&stop](const void*, int) { stop = true; });
  const int64_t end = monotonic_ns() + static_cast<int64_t>(guard_s * 1e9);
  while (!stop && monotonic_ns() < end) bus.handle_timeout(100);
  ChildResult r;
  r.ok = 1;
  return r;
}

}  // namespace

Percentiles percentiles(std::vector<int64_t>& samples_ns) {
  Percentiles p;
  p.count = static_cast<int64_t>(samples_ns.size());
  if (samples_ns.empty()) return p;
  std::sort(samples_ns.begin(), samples_ns.end());
  const auto at = [&](double q) {
    const std::size_t i =
        std::min(samples_ns.size() - 1, static_cast<std::size_t>(q * static_cast<double>(samples_ns.size())));
    return static_cast<double>(samples_ns[i]) / 1000.0;
  };
  p.p50_us = at(0.50);
  p.p99_us = at(0.99);
  p.max_us = static_cast<double>(samples_ns.back()) / 1000.0;
  return p;
}

Percentiles wake_up_floor(double rate_hz, double seconds, const FloorSettings& settings) {
  int fd = -1;
  const pid_t pid = spawn(
      [&]() -> ChildResult {
        if (const std::string e = apply(settings, 80); !e.empty()) return fail(e);
        const int64_t period = static_cast<int64_t>(1e9 / rate_hz);
        const int64_t n = static_cast<int64_t>(seconds * rate_hz);
        std::vector<int64_t> late;
        late.reserve(static_cast<std::size_t>(n));
        int64_t deadline = monotonic_ns() + 10 * period;
        for (int64_t k = 0; k < n; ++k) {
          sleep_until(deadline);
          late.push_back(monotonic_ns() - deadline);
          deadline += period;
        }
        return from_percentiles(late);
      },
      &fd);
  return to_percentiles(collect(pid, fd, "wake-up floor"));
}

Percentiles lcm_chain_floor(const std::string& url, int hops, double rate_hz, double seconds, int payload_bytes,
                            const FloorSettings& settings) {
  if (hops < 1) throw std::invalid_argument("lcm_chain_floor: hops must be >= 1");
  const double guard_s = seconds + 30.0;
  // Relays: hop i forwards FLOOR_HOP<i-1> to FLOOR_HOP<i>, unchanged.
  std::vector<std::pair<pid_t, int>> relays;
  for (int i = 1; i < hops; ++i) {
    int fd = -1;
    const pid_t pid = spawn(
        [&, i]() -> ChildResult {
          if (const std::string e = apply(settings); !e.empty()) return fail(e);
          const auto bus = open_bus(url);
          const std::string out = hop_channel(i);
          on(*bus, hop_channel(i - 1), [&](const void* data, int size) { bus->publish_bytes(out, data, size); });
          return serve(*bus, guard_s);
        },
        &fd);
    relays.emplace_back(pid, fd);
  }
  // The source: sends at rate_hz, times each message's return from the last hop.
  int fd = -1;
  const pid_t source = spawn(
      [&]() -> ChildResult {
        if (const std::string e = apply(settings); !e.empty()) return fail(e);
        const auto bus = open_bus(url);
        std::vector<int64_t> latency;
        bool echoed = false;
        on(*bus, hop_channel(hops - 1), [&](const void* data, int size) {
          int64_t head[2];
          if (size < static_cast<int>(sizeof head)) return;
          std::memcpy(head, data, sizeof head);
          if (head[0] < 0) {
            echoed = true;
          } else {
            latency.push_back(monotonic_ns() - head[1]);
          }
        });
        std::vector<unsigned char> payload(static_cast<std::size_t>(std::max(payload_bytes, 16)), 0);
        const auto send = [&](int64_t seq) {
          const int64_t head[2] = {seq, monotonic_ns()};
          std::memcpy(payload.data(), head, sizeof head);
          bus->publish_bytes(hop_channel(0), payload.data(), static_cast<int>(payload.size()));
        };
        // The chain is up when a probe comes back through every hop.
        const int64_t give_up = monotonic_ns() + 10000000000LL;
        while (!echoed && monotonic_ns() < give_up) {
          send(-1);
          handle_until(*bus, monotonic_ns() + 20000000);
        }
        if (!echoed) return fail("the chain of " + std::to_string(hops) + " hops did not come up within 10 s");
        const int64_t period = static_cast<int64_t>(1e9 / rate_hz);
        const int64_t n = static_cast<int64_t>(seconds * rate_hz);
        latency.reserve(static_cast<std::size_t>(n));
        int64_t deadline = monotonic_ns() + period;
        for (int64_t k = 0; k < n; ++k) {
          handle_until(*bus, deadline);
          send(k);
          deadline += period;
        }
        handle_until(*bus, monotonic_ns() + 100000000);  // the last ones back
        const unsigned char none = 0;
        for (int i = 0; i < 3; ++i) bus->publish_bytes(kStop, &none, 1);
        ChildResult r = from_percentiles(latency);
        r.values[4] = static_cast<double>(n);  // sent
        return r;
      },
      &fd);
  const ChildResult r = collect_group(source, fd, "LCM chain source", relays, "LCM chain relay");
  Percentiles p = to_percentiles(r);
  if (p.count < static_cast<int64_t>(0.99 * r.values[4])) {
    throw std::runtime_error("LCM chain: only " + std::to_string(p.count) + " of " +
                             std::to_string(static_cast<int64_t>(r.values[4])) + " messages came back");
  }
  return p;
}

LockstepFloor lockstep_floor(const std::string& url, int64_t step_ns,
                             const std::vector<contract::ScheduledParticipant>& participants, double sim_seconds,
                             const FloorSettings& settings) {
  const double guard_s = 120.0;
  std::vector<std::pair<pid_t, int>> children;
  for (std::size_t i = 0; i < participants.size(); ++i) {
    int fd = -1;
    const contract::ScheduledParticipant me = participants[i];
    const pid_t pid = spawn(
        [&, i, me]() -> ChildResult {
          if (const std::string e = apply(settings); !e.empty()) return fail(e);
          const auto bus = open_bus(url);
          const auto index = static_cast<int64_t>(i);
          int64_t next_due_ns = 0;
          on(*bus, kTick, [&](const void* data, int size) {
            int64_t tick[2];  // step, t
            if (size < static_cast<int>(sizeof tick)) return;
            std::memcpy(tick, data, sizeof tick);
            if (tick[0] >= 0) {
              if (tick[1] < next_due_ns) return;  // not due at this tick
              next_due_ns = me.aligned ? contract::next_due_after(tick[1], me.period_ns) : tick[1] + me.period_ns;
            }
            const int64_t ack[3] = {index, tick[0], next_due_ns};
            bus->publish_bytes(kAck, ack, sizeof ack);
          });
          return serve(*bus, guard_s);
        },
        &fd);
    children.emplace_back(pid, fd);
  }
  int fd = -1;
  const pid_t master = spawn(
      [&]() -> ChildResult {
        if (const std::string e = apply(settings); !e.empty()) return fail(e);
        const auto bus = open_bus(url);
        struct Master {
          contract::LockstepSchedule schedule;
          std::map<int64_t, bool> ready;
          int64_t acks = 0;
        } m;
        for (std::size_t i = 0; i < participants.size(); ++i) m.schedule.add(std::to_string(i));
        on(*bus, kAck, [&m](const void* data, int size) {
          int64_t ack[3];
          if (size < static_cast<int>(sizeof ack)) return;
          std::memcpy(ack, data, sizeof ack);
          if (ack[1] < 0) {
            m.ready[ack[0]] = true;
            return;
          }
          ++m.acks;
          m.schedule.acknowledge(std::to_string(ack[0]), ack[1], ack[2]);
        });
        // Every participant answers a probe before the clock starts.
        const int64_t give_up = monotonic_ns() + 10000000000LL;
        while (m.ready.size() < participants.size() && monotonic_ns() < give_up) {
          const int64_t probe[2] = {-1, 0};
          bus->publish_bytes(kTick, probe, sizeof probe);
          handle_until(*bus, monotonic_ns() + 20000000);
        }
        if (m.ready.size() < participants.size()) return fail("lockstep participants did not answer within 10 s");
        const int64_t horizon = static_cast<int64_t>(sim_seconds * 1e9);
        int64_t ticks = 0;
        const int64_t start = monotonic_ns();
        int64_t step = 0;
        for (int64_t t = 0; t < horizon; t += step_ns, ++step) {
          if (!m.schedule.tick_at(t)) continue;
          const int64_t tick[2] = {step, t};
          bus->publish_bytes(kTick, tick, sizeof tick);
          ++ticks;
          const int64_t deadline = monotonic_ns() + 2000000000LL;
          while (!m.schedule.missing(step, t).empty()) {
            if (monotonic_ns() > deadline)
              return fail("no acknowledgement of step " + std::to_string(step) + " in 2 s");
            bus->handle_timeout(100);
          }
        }
        const double wall_s = static_cast<double>(monotonic_ns() - start) / 1e9;
        const unsigned char none = 0;
        for (int i = 0; i < 3; ++i) bus->publish_bytes(kStop, &none, 1);
        ChildResult r;
        r.ok = 1;
        r.values[0] = sim_seconds / wall_s;
        r.values[1] = static_cast<double>(ticks);
        r.values[2] = static_cast<double>(m.acks);
        return r;
      },
      &fd);
  const ChildResult r = collect_group(master, fd, "lockstep master", children, "lockstep participant");
  LockstepFloor f;
  f.speed_x = r.values[0];
  f.ticks = static_cast<int64_t>(r.values[1]);
  f.acks = static_cast<int64_t>(r.values[2]);
  f.messages_per_sim_s = static_cast<double>(f.ticks + f.acks) / sim_seconds;
  return f;
}

CpuHog::CpuHog(double max_seconds) {
  const long cpus = std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN));
  for (long i = 0; i < cpus; ++i) {
    const pid_t pid = ::fork();
    if (pid == 0) {
      ::alarm(static_cast<unsigned>(std::max(1.0, max_seconds)));  // bounded: SIGALRM ends it
      volatile double x = 0.0;
      for (;;) x = x + 1.0;
    }
    if (pid > 0) pids_.push_back(pid);
  }
}

CpuHog::~CpuHog() { stop(); }

void CpuHog::stop() {
  for (pid_t pid : pids_) ::kill(pid, SIGKILL);
  for (pid_t pid : pids_) ::waitpid(pid, nullptr, 0);
  pids_.clear();
}

}  // namespace nimble::launcher::bench
