#pragma once
/// Recorder: writes every message of a run to an LCM log (lcm-logplayer, lcm::LogFile and
/// `rig identify` read it) and feeds the run monitor. Used by both executors; nothing here
/// knows where the messages come from.

#include <cstdint>
#include <cstdio>
#include <vector>
#include <memory>
#include <string>

#include "core/output_file.h"
#include "launcher/run_monitor.h"
#include "launcher/run_report.h"
#include "launcher/run_plan.h"

namespace nimble::launcher {

/// What the monitor of a run of `plan` expects: the channel rates of its processes, the
/// clock's own channels (RIG_CLOCK, STEP_ACK with the recorder as a lockstep participant,
/// but not in process), lateness in real time.
MonitorConfig monitor_config(const RunPlan& plan);

/// The bytes the LCM log of `plan` is expected to take: per channel its expected rate times an
/// event (the log's 24-byte event header, the channel's name, the message's typical size,
/// lcmjson::typical_encoded_size()) over the run's duration; the wall-clock channels at their
/// wall rate, as if the run took its simulated time (an upper bound faster than real time).
int64_t expected_log_bytes(const RunPlan& plan);

/// Before a run: "" if the run's log fits, else what is wrong, naming both numbers: a log
/// expected past its limit `max_bytes` (0: none), or (with `check_free`) past the free space of
/// its filesystem.
std::string log_space_problem(const RunPlan& plan, const std::string& log_file, int64_t max_bytes, bool check_free);

/// What the log's event timestamps follow (lcm-logplayer replays at their pace).
enum class LogStamps {
  kWallClock,  ///< the wall clock at recording (real time: the log replays as it happened)
  kSimulated,  ///< simulated time, from RIG_CLOCK (lockstep, in process: the log replays at
               ///< real speed, however fast the run was flown)
};

class Recorder {
 public:
  /// Opens `log_file` for writing (a 1 MiB write buffer; the file is the LCM log format, as
  /// lcm-logger writes it, each event one record of an OutputFile: a failed write cuts the log
  /// back to its last whole event).
  /// With LogStamps::kSimulated, events before the run's simulated time begins carry the wall
  /// clock of their receipt. It begins with the first RIG_CLOCK tick or lockstep TRUTH (a
  /// `step` >= 0: the master's first step goes out before its tick), placed at the wall clock
  /// of that message's receipt; from then on an event carries that base plus the simulated
  /// time of the newest tick (or that first truth), never less than the event before it. So
  /// the events of a run are spaced as in flight, and the log stays ordered.
  /// @throws std::runtime_error naming the file if it cannot be opened.
  Recorder(const std::string& log_file, RunMonitor& monitor, LogStamps stamps = LogStamps::kWallClock);
  ~Recorder();
  Recorder(const Recorder&) = delete;
  Recorder& operator=(const Recorder&) = delete;

  /// Logs one message, stamped as the constructor says, and hands it to the monitor (also after
  /// a failed write: the run's figures stay whole, the log keeps what it had).
  /// `recv_ns`: its receive time [ns, CLOCK_MONOTONIC]; `own_encoding` as for RunMonitor::on_message().
  /// Never throws for a failed write: failed() says so, and the run ends on it.
  void record(const std::string& channel, const void* data, int size, int64_t recv_ns, bool own_encoding = false);

  /// Flushes the log if `flush_period_ns` has passed since the last flush (what is recorded
  /// survives a crash of the recorder up to that age).
  void flush_if_due(int64_t now_ns, int64_t flush_period_ns = 100000000LL);
  /// Flushes the log.
  void flush();
  /// Flushes, syncs and closes the log (the end of a run): a failure here is failed() too.
  void close();

  /// The log's size limit in bytes (0: none): reaching it ends the recording as a full disk does.
  void set_max_bytes(int64_t bytes) { log_.set_max_bytes(bytes); }

  /// Whether a write of the log failed: the log then holds its whole events before the failure.
  bool failed() const { return !failure_.empty(); }
  /// What the log holds (after close(), for sure).
  LogKept kept() const;

  int64_t events() const { return event_number_; }
  const std::string& file() const { return file_; }

 private:
  /// Runs `write` on the log; a failure is kept in failure_ (the log is cut back to whole events).
  template <typename Write>
  void checked(Write&& write);
  /// Drops the times of events known to be in the file but the newest.
  void forget_kept();

  std::string file_;
  RunMonitor& monitor_;
  OutputFile log_;
  std::string failure_;
  std::string header_;  ///< one event's header and channel, reused
  int64_t event_number_ = 0;
  /// The simulated time of each event not yet known to be in the file (a whole buffer at most),
  /// and of the newest one that is: what kept() tells after a failure.
  std::vector<double> pending_sim_s_;
  int64_t pending_first_ = 0;  ///< the event number of pending_sim_s_[0]
  double kept_sim_s_ = 0.0;
  int64_t last_flush_ns_ = 0;
  /// The timestamp of `channel`'s event now [us].
  int64_t stamp_us(const std::string& channel, const void* data, int size, int64_t recv_ns);
  /// The wall clock [us] of a receipt at `recv_ns` (CLOCK_MONOTONIC; 0: now).
  int64_t received_wall_us(int64_t recv_ns) const;
  /// Simulated time `sim_utime` [us] was received at `recv_ns`: sets sim_base_us_.
  void place_simulated_time(int64_t sim_utime, int64_t recv_ns);
  LogStamps stamps_;
  int64_t sim_base_us_ = -1;             ///< simulated: the wall clock of sim time 0 (-1: no tick yet)
  int64_t wall_minus_monotonic_us_ = 0;  ///< the wall clock less CLOCK_MONOTONIC at opening [us]
  int64_t last_stamp_us_ = 0;
};

}  // namespace nimble::launcher
