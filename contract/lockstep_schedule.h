#pragma once
/// The lockstep schedule: when the master (the plant) sends a RIG_CLOCK tick and whom it
/// waits for. One rule, used by the master in transport/node.cc and replayed by the expected
/// rates of RIG_CLOCK and STEP_ACK (contract/rates.cc), so the two cannot drift apart.
///
/// The master steps every plant period. At a step of time t it ticks if some participant is
/// due (its next due time <= t), and steps on once every due participant has acknowledged the
/// step, each acknowledgement carrying the participant's next due time: for a process with
/// a periodic task, the first multiple of the task's period after t (next_due_after); for the
/// launcher's recorder, t plus its period.

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace nimble::contract {

/// The first multiple of `period_ns` after `t_ns`: when a task of that period that ran at the
/// tick at `t_ns` is next due.
inline int64_t next_due_after(int64_t t_ns, int64_t period_ns) { return (t_ns / period_ns + 1) * period_ns; }

class LockstepSchedule {
 public:
  /// A participant, first due at `first_due_ns`.
  void add(const std::string& participant, int64_t first_due_ns = 0) {
    entries_[participant] = Entry{first_due_ns, -1};
  }
  bool has(const std::string& participant) const { return entries_.count(participant) > 0; }
  /// True if some participant is due at step time `t_ns`: the master ticks.
  bool tick_at(int64_t t_ns) const {
    for (const auto& [name, e] : entries_) {
      if (e.next_due_ns <= t_ns) return true;
    }
    return false;
  }
  /// The participants due at `t_ns`.
  std::vector<std::string> due_at(int64_t t_ns) const {
    std::vector<std::string> due;
    for (const auto& [name, e] : entries_) {
      if (e.next_due_ns <= t_ns) due.push_back(name);
    }
    return due;
  }
  /// `participant` acknowledged `step` and is next due at `next_due_ns`. An unknown
  /// participant is ignored (returns false); an older step than one already acknowledged
  /// leaves the record as it is.
  bool acknowledge(const std::string& participant, int64_t step, int64_t next_due_ns) {
    const auto it = entries_.find(participant);
    if (it == entries_.end()) return false;
    if (step >= it->second.last_ack_step) {
      it->second.last_ack_step = step;
      it->second.next_due_ns = next_due_ns;
    }
    return true;
  }
  /// A participant due at `t_ns` that has not yet acknowledged `step`, or "" if none.
  std::string missing(int64_t step, int64_t t_ns) const {
    for (const auto& [name, e] : entries_) {
      if (e.next_due_ns <= t_ns && e.last_ack_step < step) return name;
    }
    return "";
  }

 private:
  struct Entry {
    int64_t next_due_ns = 0;
    int64_t last_ack_step = -1;
  };
  std::map<std::string, Entry> entries_;
};

/// A participant of a replayed schedule: its period, and whether it is next due at the next
/// multiple of the period (a process's task) or one period after the tick (the recorder).
struct ScheduledParticipant {
  int64_t period_ns = 0;
  bool aligned = true;
};

/// RIG_CLOCK ticks and STEP_ACK acknowledgements of a master stepping every `step_ns` from 0
/// to before `horizon_ns`, with these participants, all first due at 0.
struct LockstepCounts {
  int64_t ticks = 0;
  int64_t acks = 0;
};
inline LockstepCounts replay_lockstep(int64_t step_ns, const std::vector<ScheduledParticipant>& participants,
                                      int64_t horizon_ns) {
  LockstepSchedule schedule;
  for (std::size_t i = 0; i < participants.size(); ++i) schedule.add(std::to_string(i));
  LockstepCounts counts;
  int64_t step = 0;
  for (int64_t t = 0; t < horizon_ns; t += step_ns, ++step) {
    if (!schedule.tick_at(t)) continue;
    ++counts.ticks;
    for (const std::string& name : schedule.due_at(t)) {
      const ScheduledParticipant& p = participants[std::stoul(name)];
      ++counts.acks;
      schedule.acknowledge(name, step, p.aligned ? next_due_after(t, p.period_ns) : t + p.period_ns);
    }
  }
  return counts;
}

}  // namespace nimble::contract
