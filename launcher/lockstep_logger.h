#pragma once
/// LockstepLogger: the launcher's log as a lockstep participant.
///
/// It acknowledges a tick once it has logged everything before it, every logger_period_ms of
/// simulated time, so that a lockstep run can never outpace its log (no message lost, whatever
/// the load). It also follows the other participants' acknowledgements (their next due time),
/// so that the launcher knows whether the next tick is one it must answer: only then does it
/// need to wake for each message; otherwise it reads what came every so often.

#include <cstdint>
#include <functional>
#include <map>
#include <string>

#include <nimble/step_ack_t.hpp>

namespace nimble::launcher {

class LockstepLogger {
 public:
  /// The logger's name among the participants.
  inline static const std::string kName = "logger";

  /// `period_ns`: simulated time between the ticks it answers; `publish_ack` sends a STEP_ACK.
  LockstepLogger(int64_t period_ns, std::function<void(const step_ack_t&)> publish_ack)
      : period_ns_(period_ns), publish_ack_(std::move(publish_ack)) {}

  /// One message of the run, in the order logged: a RIG_CLOCK tick the logger is due at is
  /// answered; another participant's STEP_ACK updates when it is due next.
  void on_message(const std::string& channel, const void* data, int size);

  /// True if the next tick may be one the logger must answer: no other participant is known to
  /// be due before the logger. False means the launcher may read the run's messages late.
  bool may_be_due_next() const;

 private:
  int64_t period_ns_;
  std::function<void(const step_ack_t&)> publish_ack_;
  int64_t next_due_ns_ = 0;
  int64_t ack_seq_ = 0;
  std::map<std::string, int64_t> others_next_due_ns_;  ///< from their latest STEP_ACK
};

}  // namespace nimble::launcher
