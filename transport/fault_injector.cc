#include "transport/fault_injector.h"

#include <algorithm>
#include <limits>

#include "transport/bus.h"

namespace nimble::transport {

using contract::FaultKind;

FaultInjector::FaultInjector(const std::vector<contract::FaultSpec>& faults, uint64_t seed, Announce announce)
    : announce_(std::move(announce)) {
  for (const auto& f : faults) {
    if (f.target != contract::kFaultTargetCan) faults_.push_back(f);
  }
  for (const auto& f : faults_) {
    // One stream per fault, from the run's seed and the fault's place in the list.
    std::seed_seq seq{static_cast<uint32_t>(seed), static_cast<uint32_t>(seed >> 32), static_cast<uint32_t>(f.index),
                      0x6661756cu};
    rng_.emplace(f.index, std::mt19937_64(seq));
  }
  for (const auto& f : faults_) channels_[f.target].faults.push_back(&f);
}

void FaultInjector::release_due(Bus& bus, const std::string& channel, ChannelState& cs, int64_t utime) {
  while (!cs.delayed.empty() && cs.delayed.front().release_utime <= utime) {
    const auto& b = cs.delayed.front().bytes;
    bus.publish_bytes(channel, b.data(), static_cast<int>(b.size()));
    cs.delayed.pop_front();
  }
}

void FaultInjector::publish(Bus& bus, const std::string& channel, FaultableMessage& msg) {
  ChannelState& cs = channels_.at(channel);
  // Decided at rig time; a message keeps its own stamp (the IMU's clock may differ).
  const int64_t t = msg.rig_utime ? *msg.rig_utime : *msg.utime;
  const int64_t stamp = *msg.utime;
  release_due(bus, channel, cs, t);

  const contract::FaultSpec* f = nullptr;
  for (const auto* candidate : cs.faults) {
    if (candidate->active_at(t)) {
      f = candidate;
      break;
    }
  }
  const int now_active = f != nullptr ? f->index : -1;
  if (now_active != cs.active) {
    if (cs.active >= 0 && announce_) {
      for (const auto* old : cs.faults) {
        if (old->index == cs.active) announce_(*old, false, t);
      }
    }
    if (f != nullptr && announce_) announce_(*f, true, t);
    cs.active = now_active;
  }
  // Sent at `release` (now if due and nothing waits), always behind the messages still waiting:
  // order and seq are kept.
  const auto send_at = [&](int64_t release, std::vector<uint8_t> bytes) {
    if (cs.delayed.empty() && release <= t) {
      bus.publish_bytes(channel, bytes.data(), static_cast<int>(bytes.size()));
    } else {
      const int64_t after = cs.delayed.empty() ? release : std::max(release, cs.delayed.back().release_utime);
      cs.delayed.push_back({after, std::move(bytes)});
    }
  };
  const auto send_now = [&](std::vector<uint8_t> bytes) { send_at(t, std::move(bytes)); };

  if (f == nullptr) {
    *msg.seq = cs.next_seq++;
    cs.last_good = msg.encode();
    send_now(cs.last_good);
    return;
  }
  std::mt19937_64& rng = rng_.at(f->index);
  switch (f->kind) {
    case FaultKind::kOff: ++withheld_; return;
    case FaultKind::kStuck: {
      if (cs.held_for != f->index) {
        cs.held = cs.last_good.empty() ? msg.encode() : cs.last_good;
        cs.held_for = f->index;
      }
      msg.restore(cs.held);
      *msg.utime = stamp;
      *msg.seq = cs.next_seq++;
      send_now(msg.encode());
      return;
    }
    case FaultKind::kGarbage: {
      if (f->garbage_nan) {
        for (auto& [name, value] : msg.values) {
          if (contract::field_selected(f->field, name)) *value = std::numeric_limits<double>::quiet_NaN();
        }
        *msg.seq = cs.next_seq++;
        send_now(msg.encode());
        return;
      }
      // The type's fingerprint, then random bytes: it looks like the type and does not decode
      // (or decodes to a seq that does not continue the publisher's). It takes no seq.
      *msg.seq = cs.next_seq;
      std::vector<uint8_t> bytes = msg.encode();
      for (std::size_t i = 8; i < bytes.size(); ++i) bytes[i] = static_cast<uint8_t>(rng() & 0xff);
      ++withheld_;
      send_now(std::move(bytes));
      return;
    }
    case FaultKind::kWrong:
      for (auto& [name, value] : msg.values) {
        if (contract::field_selected(f->field, name)) *value = *value * f->scale + f->bias;
      }
      *msg.seq = cs.next_seq++;
      send_now(msg.encode());
      return;
    case FaultKind::kSlow:
      if (cs.slow_for != f->index) {
        cs.slow_for = f->index;
        cs.slow_count = 0;
      }
      if (cs.slow_count++ % f->divisor != 0) {
        ++withheld_;
        return;
      }
      *msg.seq = cs.next_seq++;
      send_now(msg.encode());
      return;
    case FaultKind::kDelayed: {
      *msg.seq = cs.next_seq++;
      send_at(t + f->delay_us, msg.encode());
      return;
    }
    case FaultKind::kIntermittent: {
      *msg.seq = cs.next_seq++;  // lost on the way: a gap the consumers count
      std::uniform_real_distribution<double> u(0.0, 1.0);
      if (u(rng) < f->probability) {
        ++withheld_;
        return;
      }
      send_now(msg.encode());
      return;
    }
    case FaultKind::kCanLoss:
    case FaultKind::kCanCorrupt:
    case FaultKind::kCanBusOff:
      // Faults of the CAN link act on its frames (can_bridge/can_faults.h), never on a channel:
      // the scenario loader gives them no channel target.
      *msg.seq = cs.next_seq++;
      send_now(msg.encode());
      return;
  }
}

}  // namespace nimble::transport
