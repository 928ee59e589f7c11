#pragma once
/// The machine's floors for the rig's timing figures, measured by `bench_rig` in the same run
/// as the rig itself: what the hardware, the kernel and LCM allow with no rig code at all.
///
///  - wake_up_floor: a bare periodic wake-up at 1 kHz under SCHED_FIFO (what cyclictest
///    measures): the best jitter any 1 kHz loop on this machine can have.
///  - lcm_chain_floor: a bare LCM chain with the hops of the rig's control path (plant ->
///    [estimator ->] controller -> plant), each hop its own process, on the rig's LCM URL,
///    CPUs and priority, forwarding raw bytes: the best control-loop latency the transport allows.
///    The chain and the lockstep floor run on the rig's own transport (transport::Bus: LCM's
///    publish and wire format, received on the process's own thread as the rig's processes
///    receive, transport/multicast_tap.h), so a floor costs what a hop of the rig costs.
///  - lockstep_floor: a bare lockstep master and the rig's participants, each its own process,
///    ticking the rig's schedule with empty steps (fan-out of RIG_CLOCK-sized ticks, fan-in of
///    acknowledgements): the fastest the rig could run in lockstep over this transport.
///  - CpuHog: a bounded background load, one busy process per CPU.
///
/// Every measurement runs in child processes forked from a process without threads (the caller
/// must not have started LCM), inside whatever network namespace the caller is in.

#include <sys/types.h>

#include <cstdint>
#include <string>
#include <vector>

#include "contract/lockstep_schedule.h"

namespace nimble::launcher::bench {

/// How the measuring processes run: the rig's own settings, so the floor is comparable.
struct FloorSettings {
  int priority = 0;       ///< SCHED_FIFO priority, 0: the default scheduler
  std::vector<int> cpus;  ///< CPU affinity (empty: any)
};

/// Percentiles of a set of durations [us].
struct Percentiles {
  double p50_us = 0.0, p99_us = 0.0, max_us = 0.0;
  int64_t count = 0;
};

/// Percentiles of `samples_ns` (sorted in place).
Percentiles percentiles(std::vector<int64_t>& samples_ns);

/// Wake-up lateness behind absolute CLOCK_MONOTONIC deadlines at `rate_hz` for `seconds`, in a
/// child process with `settings` (priority 0 there means: SCHED_FIFO 80, as cyclictest -p 80).
/// @throws std::runtime_error if the child fails.
Percentiles wake_up_floor(double rate_hz, double seconds, const FloorSettings& settings);

/// Round trip of `payload_bytes` messages sent at `rate_hz` for `seconds` through `hops` LCM
/// hops (hops - 1 relay processes and the source, which times each message back), on `url`.
/// @throws std::runtime_error if a process fails or the chain does not come up.
Percentiles lcm_chain_floor(const std::string& url, int hops, double rate_hz, double seconds, int payload_bytes,
                            const FloorSettings& settings);

/// Result of a bare lockstep run.
struct LockstepFloor {
  double speed_x = 0.0;             ///< simulated / wall time
  double messages_per_sim_s = 0.0;  ///< ticks + acknowledgements per simulated second
  int64_t ticks = 0, acks = 0;
};

/// A lockstep master stepping every `step_ns` for `sim_seconds` with `participants` (each its
/// own process, the rig's schedule rule), on `url`.
/// @throws std::runtime_error if a process fails or an acknowledgement does not come.
LockstepFloor lockstep_floor(const std::string& url, int64_t step_ns,
                             const std::vector<contract::ScheduledParticipant>& participants, double sim_seconds,
                             const FloorSettings& settings);

/// One busy-looping process per online CPU at the default priority, until stop() or the
/// destructor, and never longer than `max_seconds` (each hog ends itself).
class CpuHog {
 public:
  explicit CpuHog(double max_seconds);
  ~CpuHog();
  CpuHog(const CpuHog&) = delete;
  CpuHog& operator=(const CpuHog&) = delete;
  void stop();
  int processes() const { return static_cast<int>(pids_.size()); }

 private:
  std::vector<pid_t> pids_;
};

}  // namespace nimble::launcher::bench
