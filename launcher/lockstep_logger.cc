// LockstepLogger (launcher/lockstep_logger.h): the launcher's log as a lockstep participant.

#include "launcher/lockstep_logger.h"

#include <nimble/rig_clock_t.hpp>

#include "contract/channels.h"
#include "contract/decode.h"

namespace nimble::launcher {

void LockstepLogger::on_message(const std::string& channel, const void* data, int size) {
  if (channel == contract::channels::kRigClock) {
    rig_clock_t tick{};
    if (!contract::decode_exact(data, size, tick) || tick.sim_time_ns < next_due_ns_) return;
    next_due_ns_ = tick.sim_time_ns + period_ns_;
    step_ack_t ack{};
    ack.utime = tick.utime;
    ack.seq = ack_seq_++;
    ack.step = tick.step;
    ack.next_due_ns = next_due_ns_;
    ack.process = kName;
    publish_ack_(ack);
  } else if (channel == contract::channels::kStepAck) {
    step_ack_t ack{};
    if (contract::decode_exact(data, size, ack) && ack.process != kName)
      others_next_due_ns_[ack.process] = ack.next_due_ns;
  }
}

bool LockstepLogger::may_be_due_next() const {
  // The master ticks at the earliest due time of all participants; the logger's own is among
  // them. Until every other participant has answered once, assume the worst.
  if (others_next_due_ns_.empty()) return true;
  int64_t earliest = next_due_ns_;
  for (const auto& [name, due] : others_next_due_ns_) earliest = due < earliest ? due : earliest;
  return next_due_ns_ <= earliest;
}

}  // namespace nimble::launcher
