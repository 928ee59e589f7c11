#pragma once
/// InprocessHub: the message exchange of a run flown in one process (`rig run --clock
/// inprocess`). Every node's Bus publishes into one first-in first-out queue of encoded
/// messages (the bytes LCM would carry) and drain() hands each to every subscription whose
/// channel pattern matches, in publication order, on the calling thread. No sockets, no
/// threads, no copies beyond the one encode.
///
/// A subscription's pattern is a regular expression matched against the whole channel name
/// (LCM's rule; an exact name matches itself). Pollers stand in for descriptors a process
/// also waits on (the in-process CAN link): drain() calls them whenever the queue is empty
/// and stops once neither the queue nor any poller has anything left.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <functional>
#include <string>
#include <unordered_map>
#include <vector>

namespace nimble::transport {

class InprocessHub {
 public:
  /// Gets channel, encoded bytes and size.
  using Handler = std::function<void(const std::string& channel, const void* data, int size)>;
  /// Handles what is waiting; returns true if it did anything.
  using Poller = std::function<bool()>;

  /// Adds a subscription; `pattern` is a regular expression over the whole channel name.
  /// @throws std::regex_error for a malformed pattern.
  void subscribe(const std::string& pattern, Handler handler);
  /// Adds a poller (see above).
  void add_poller(Poller poller) { pollers_.push_back(std::move(poller)); }

  /// Queues one message (copied). Safe to call from a handler. `own_encoding`: the bytes are
  /// what the rig's own encoder wrote for a message (Bus::publish), not bytes from elsewhere
  /// (Bus::publish_bytes: fault injection's garbage, a log, a bridge).
  void publish(const std::string& channel, const void* data, int size, bool own_encoding = false);

  /// Delivers queued messages (and those their handlers publish) until nothing is left;
  /// returns how many were delivered. A handler's nested drain() returns 0 at once.
  int64_t drain();

  /// While a handler runs: true if the message it is given was written by the rig's own
  /// encoder (see publish()), so that decoding it needs no check that it encodes back
  /// (contract::decode_as()).
  bool delivering_own_encoding() const { return delivering_own_; }

  /// Messages published so far.
  int64_t published() const { return published_; }
  /// Messages waiting.
  std::size_t waiting() const { return count_ - head_; }

 private:
  struct Entry {
    int channel = 0;   // index into names_
    bool own = false;  // written by the rig's own encoder
    std::vector<unsigned char> data;
  };
  int intern(const std::string& channel);
  const std::vector<int>& targets(int channel);

  std::vector<std::string> patterns_;
  std::vector<Handler> handlers_;
  std::vector<Poller> pollers_;
  std::deque<std::string> names_;  // stable references while handlers run
  std::unordered_map<std::string, int> ids_;
  /// Channel ids by the address of the caller's name: publishers pass the same long-lived
  /// strings (contract/channels.h) every time, so a hit costs one comparison instead of a
  /// hash; a hit is only taken when the names are equal, so another string at a reused
  /// address is looked up as usual.
  struct RecentName {
    const std::string* name = nullptr;
    int id = -1;
  };
  static constexpr std::size_t kRecentNames = 32;
  RecentName recent_[kRecentNames];
  std::vector<std::vector<int>> targets_;
  std::vector<char> targets_valid_;  // per channel: targets_ is up to date (char: read per delivery)
  std::vector<Entry> queue_;         // entries [head_, count_) wait; their buffers are reused
  std::size_t head_ = 0, count_ = 0;
  bool draining_ = false;
  bool delivering_own_ = false;
  int64_t published_ = 0;
};

}  // namespace nimble::transport
