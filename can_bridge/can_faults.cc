#include "can_bridge/can_faults.h"

namespace nimble::can {
namespace {

/// SplitMix64's finaliser: a well-mixed 64-bit value from any input.
uint64_t mix(uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31);
}

}  // namespace

CanLinkFaults::CanLinkFaults(const std::vector<contract::FaultSpec>& faults, uint64_t seed) : seed_(seed) {
  for (const auto& f : faults) {
    if (f.target == contract::kFaultTargetCan) faults_.push_back(f);
  }
}

double CanLinkFaults::uniform(const contract::FaultSpec& f, Direction d, int64_t message, int frame,
                              uint64_t salt) const {
  uint64_t h = mix(seed_);
  h = mix(h ^ static_cast<uint64_t>(f.index));
  h = mix(h ^ static_cast<uint64_t>(d));
  h = mix(h ^ static_cast<uint64_t>(message));
  h = mix(h ^ (static_cast<uint64_t>(frame) << 8 | salt));
  return static_cast<double>(h >> 11) * 0x1.0p-53;
}

const contract::FaultSpec* CanLinkFaults::active_at(int64_t utime) const {
  for (const auto& f : faults_) {
    if (f.active_at(utime)) return &f;
  }
  return nullptr;
}

const contract::FaultSpec* CanLinkFaults::bus_off_at(int64_t utime) const {
  const contract::FaultSpec* f = active_at(utime);
  return f != nullptr && f->kind == contract::FaultKind::kCanBusOff ? f : nullptr;
}

CanLinkFaults::Fate CanLinkFaults::fate(Direction d, int64_t message, int frame, int64_t utime, int data_len,
                                        int* bit) const {
  const contract::FaultSpec* f = active_at(utime);
  if (f == nullptr) return Fate::kSent;
  switch (f->kind) {
    case contract::FaultKind::kCanBusOff: return Fate::kBusOff;
    case contract::FaultKind::kCanLoss:
      return uniform(*f, d, message, frame, 0) < f->probability ? Fate::kLost : Fate::kSent;
    case contract::FaultKind::kCanCorrupt:
      if (uniform(*f, d, message, frame, 0) >= f->probability || data_len <= 0) return Fate::kSent;
      if (bit != nullptr) *bit = static_cast<int>(uniform(*f, d, message, frame, 1) * 8.0 * data_len);
      return Fate::kCorrupted;
    case contract::FaultKind::kOff:
    case contract::FaultKind::kStuck:
    case contract::FaultKind::kGarbage:
    case contract::FaultKind::kWrong:
    case contract::FaultKind::kSlow:
    case contract::FaultKind::kDelayed:
    case contract::FaultKind::kIntermittent:
      return Fate::kSent;  // faults of a channel act at its publisher (transport/fault_injector.h)
  }
  return Fate::kSent;
}

bool CanLinkFaults::arrives(Direction d, int64_t message, int frames, int64_t utime) const {
  for (int j = 0; j < frames; ++j) {
    if (fate(d, message, j, utime, 8, nullptr) != Fate::kSent) return false;
  }
  return true;
}

}  // namespace nimble::can
