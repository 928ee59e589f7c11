#pragma once
/// Faults of the CAN link (scenario `faults` with target CAN): frame loss, corruption and
/// bus-off, applied by each side of the bridge to the frames it transmits.
///
/// Every decision is a pure function of the run's seed, the fault, the direction, the message's
/// number in its direction and the frame's place in it (not of a random stream's position), so
/// that the rig side can tell, in lockstep, that a control cycle's command will never arrive:
/// it then acknowledges the cycle without it instead of waiting (the plant flies on its last
/// command, as on the real link). In real time nothing waits and the decisions are the same.

#include <cstdint>
#include <vector>

#include "contract/faults.h"

namespace nimble::can {

class CanLinkFaults {
 public:
  enum class Direction : uint64_t { kCommand = 1, kFeedback = 2 };
  enum class Fate { kSent, kLost, kCorrupted, kBusOff };

  /// Keeps the faults with target CAN; `seed` is the run's.
  CanLinkFaults(const std::vector<contract::FaultSpec>& faults, uint64_t seed);

  bool empty() const { return faults_.empty(); }

  /// The fate of frame `frame` of message number `message` (0, 1, ... in direction `d`) whose
  /// message time is `utime` [us, simulated]. For kCorrupted, *bit is the data bit to flip, in
  /// [0, 8 * data_len).
  Fate fate(Direction d, int64_t message, int frame, int64_t utime, int data_len, int* bit) const;

  /// True if every one of the `frames` frames of that message arrives intact.
  bool arrives(Direction d, int64_t message, int frames, int64_t utime) const;

  /// The bus-off fault active at `utime`, or nullptr.
  const contract::FaultSpec* bus_off_at(int64_t utime) const;
  /// The fault active at `utime` (the first in the list), or nullptr.
  const contract::FaultSpec* active_at(int64_t utime) const;

 private:
  /// Uniform in [0, 1) from the decision's identity.
  double uniform(const contract::FaultSpec& f, Direction d, int64_t message, int frame, uint64_t salt) const;

  std::vector<contract::FaultSpec> faults_;
  uint64_t seed_;
};

}  // namespace nimble::can
