#include "transport/inprocess_hub.h"

#include <algorithm>
#include <cstdint>
#include <regex>

namespace nimble::transport {

void InprocessHub::subscribe(const std::string& pattern, Handler handler) {
  std::regex check(pattern);  // throws for a malformed pattern, here rather than at delivery
  (void)check;
  patterns_.push_back(pattern);
  handlers_.push_back(std::move(handler));
  std::fill(targets_valid_.begin(), targets_valid_.end(), 0);
}

int InprocessHub::intern(const std::string& channel) {
  RecentName& recent = recent_[(reinterpret_cast<std::uintptr_t>(&channel) >> 5) % kRecentNames];
  if (recent.name == &channel && names_[static_cast<std::size_t>(recent.id)] == channel) return recent.id;
  const auto it = ids_.find(channel);
  if (it != ids_.end()) {
    recent = RecentName{&channel, it->second};
    return it->second;
  }
  recent = RecentName{&channel, static_cast<int>(names_.size())};
  ids_.emplace(channel, static_cast<int>(names_.size()));
  names_.push_back(channel);
  targets_.emplace_back();
  targets_valid_.push_back(0);
  return static_cast<int>(names_.size() - 1);
}

const std::vector<int>& InprocessHub::targets(int channel) {
  if (!targets_valid_[channel]) {
    std::vector<int>& t = targets_[channel];
    t.clear();
    for (std::size_t i = 0; i < patterns_.size(); ++i) {
      if (std::regex_match(names_[channel], std::regex(patterns_[i]))) t.push_back(static_cast<int>(i));
    }
    targets_valid_[channel] = 1;
  }
  return targets_[channel];
}

void InprocessHub::publish(const std::string& channel, const void* data, int size, bool own_encoding) {
  if (count_ == queue_.size()) queue_.emplace_back();
  Entry& e = queue_[count_++];
  e.channel = intern(channel);
  e.own = own_encoding;
  const auto* bytes = static_cast<const unsigned char*>(data);
  e.data.assign(bytes, bytes + std::max(0, size));
  ++published_;
}

int64_t InprocessHub::drain() {
  if (draining_) return 0;
  draining_ = true;
  int64_t delivered = 0;
  for (;;) {
    while (head_ < count_) {
      // Handlers may publish (the queue grows and its entries move, but a buffer stays where it
      // is) or subscribe (targets are recomputed), so only indices are held across a call.
      const std::size_t index = head_++;
      const int channel = queue_[index].channel;
      const unsigned char* data = queue_[index].data.data();
      const int size = static_cast<int>(queue_[index].data.size());
      delivering_own_ = queue_[index].own;
      for (std::size_t k = 0;; ++k) {
        const std::vector<int>& t = targets(channel);  // again after each handler, which may subscribe
        if (k >= t.size()) break;
        handlers_[t[k]](names_[channel], data, size);
      }
      delivering_own_ = false;
      ++delivered;
    }
    head_ = count_ = 0;
    bool polled = false;
    for (auto& p : pollers_) polled = p() || polled;
    if (!polled && head_ == count_) break;
  }
  draining_ = false;
  return delivered;
}

}  // namespace nimble::transport
