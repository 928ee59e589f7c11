#pragma once
/// FaultInjector: applies the scenario's faults (contract/faults.h) to the messages a process
/// publishes, inside its Bus, before they are encoded for the wire.
///
/// Injected at the publisher, a fault is seen the same by every consumer, and a lockstep run
/// stays deterministic: every decision depends only on the message's simulated time (utime)
/// and on random numbers drawn from the run's seed.
///
/// On a faulted channel the injector owns the publisher's seq: messages that are not sent
/// (off, slow) leave no gap, as a sensor that stopped or slowed down; messages lost on the way
/// (intermittent) do, and consumers count them as drops. Malformed bytes (garbage) carry no
/// valid seq and use none. Delayed messages keep their order: while any wait, later messages
/// queue behind them. A delayed message goes out with the channel's first publication at or
/// after its due time, so the delay's resolution is the channel's period.

#include <cstdint>
#include <deque>
#include <functional>
#include <map>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "contract/faults.h"

namespace nimble::transport {

class Bus;

/// A message on its way through the injector, whatever its type: its stamps, value fields and
/// codec (Bus::publish builds it around a copy of the message).
struct FaultableMessage {
  int64_t* utime = nullptr;
  /// The rig time [us] the faults are decided at, when the message's utime is another clock's
  /// (the IMU's stamps); empty: *utime.
  std::optional<int64_t> rig_utime;
  int64_t* seq = nullptr;
  contract::ValueFields values;
  std::function<std::vector<uint8_t>()> encode;
  /// Decodes `bytes` (an earlier encode()) into the message, every field.
  std::function<void(const std::vector<uint8_t>&)> restore;
};

class FaultInjector {
 public:
  /// Called when a fault begins (`began`) or ends on its channel, at simulated time `utime`.
  using Announce = std::function<void(const contract::FaultSpec& fault, bool began, int64_t utime)>;

  /// Applies the channel faults of `faults` (CAN faults are the bridge's); `seed` is the run's.
  FaultInjector(const std::vector<contract::FaultSpec>& faults, uint64_t seed, Announce announce);

  /// True if some fault targets `channel`.
  bool targets(const std::string& channel) const { return channels_.count(channel) != 0; }

  /// Publishes `msg` on `channel` through `bus` as the faults active at its utime make it.
  void publish(Bus& bus, const std::string& channel, FaultableMessage& msg);

  /// Messages lost (intermittent), not sent (off, slow) and malformed (garbage bytes) so far.
  int64_t withheld() const { return withheld_; }

 private:
  struct Delayed {
    int64_t release_utime;
    std::vector<uint8_t> bytes;
  };
  struct ChannelState {
    std::vector<const contract::FaultSpec*> faults;  ///< in list order; the first active one applies
    int64_t next_seq = 0;
    int active = -1;                 ///< index of the fault active at the last message, -1 none
    std::vector<uint8_t> last_good;  ///< the last message sent without a fault
    std::vector<uint8_t> held;       ///< stuck: the message repeated
    int held_for = -1;
    int64_t slow_count = 0;
    int slow_for = -1;
    std::deque<Delayed> delayed;
  };

  void release_due(Bus& bus, const std::string& channel, ChannelState& cs, int64_t utime);

  std::vector<contract::FaultSpec> faults_;
  std::map<int, std::mt19937_64> rng_;  ///< one stream per fault, by its index
  std::map<std::string, ChannelState> channels_;
  Announce announce_;
  int64_t withheld_ = 0;
};

}  // namespace nimble::transport
