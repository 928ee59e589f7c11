#pragma once
/// Recorder: writes every message of a run to an LCM log (lcm-logplayer, lcm::LogFile and
/// `rig identify` read it) and feeds the run monitor. Used by both executors; nothing here
/// knows where the messages come from.

#include <cstdint>
#include <cstdio>
#include <memory>
#include <string>

#include <lcm/lcm-cpp.hpp>

#include "launcher/run_monitor.h"
#include "launcher/run_plan.h"

namespace nimble::launcher {

/// What the monitor of a run of `plan` expects: the channel rates of its processes, the
/// clock's own channels (RIG_CLOCK, STEP_ACK with the recorder as a lockstep participant,
/// but not in process), lateness in real time.
MonitorConfig monitor_config(const RunPlan& plan);

/// What the log's event timestamps follow (lcm-logplayer replays at their pace).
enum class LogStamps {
  kWallClock,  ///< the wall clock at recording (real time: the log replays as it happened)
  kSimulated,  ///< simulated time, from RIG_CLOCK (lockstep, in process: the log replays at
               ///< real speed, however fast the run was flown)
};

class Recorder {
 public:
  /// Opens `log_file` for writing (a 1 MiB write buffer).
  /// With LogStamps::kSimulated, events before the first RIG_CLOCK tick carry the wall clock;
  /// from the first tick on, an event carries the wall clock of that tick plus the simulated
  /// time of the newest tick recorded, never less than the event before it. So the events of a
  /// run are spaced as in flight, and the log stays ordered.
  /// @throws std::runtime_error naming the file if it cannot be opened.
  Recorder(const std::string& log_file, RunMonitor& monitor, LogStamps stamps = LogStamps::kWallClock);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Logs one message, stamped as the constructor says, and hands it to the monitor.
  /// `recv_ns`: its receive time [ns, CLOCK_MONOTONIC]; `own_encoding` as for RunMonitor::on_message().
  void record(const std::string& channel, const void* data, int size, int64_t recv_ns, bool own_encoding = false);

  /// Flushes the log if `flush_period_ns` has passed since the last flush (what is recorded
  /// survives a crash of the recorder up to that age).
  void flush_if_due(int64_t now_ns, int64_t flush_period_ns = 100000000LL);
  /// Flushes the log.
  void flush();

  int64_t events() const { return event_number_; }
  const std::string& file() const { return file_; }

 private:
  std::string file_;
  RunMonitor& monitor_;
  std::unique_ptr<lcm::LogFile> log_;
  std::unique_ptr<char[]> buffer_;
  int64_t event_number_ = 0;
  int64_t last_flush_ns_ = 0;
  /// The timestamp of `channel`'s event now [us].
  int64_t stamp_us(const std::string& channel, const void* data, int size);
  LogStamps stamps_;
  int64_t sim_base_us_ = -1;  ///< simulated: the wall clock of sim time 0 (-1: no tick yet)
  int64_t last_stamp_us_ = 0;
};

}  // namespace nimble::launcher
