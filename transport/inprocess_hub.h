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

  /// Queues one message (copied). Safe to call from a handler.
  void publish(const std::string& channel, const void* data, int size);

  /// Delivers queued messages (and those their handlers publish) until nothing is left;
  /// returns how many were delivered. A handler's nested drain() returns 0 at once.
  int64_t drain();

  /// Messages published so far.
  int64_t published() const { return published_; }
  /// Messages waiting.
  std::size_t waiting() const { return count_ - head_; }

 private:
  struct Entry {
    int channel = 0;  // index into names_
    std::vector<unsigned char> data;
  };
  int intern(const std::string& channel);
  const std::vector<int>& targets(int channel);

  std::vector<std::string> patterns_;
  std::vector<Handler> handlers_;
  std::vector<Poller> pollers_;
  std::deque<std::string> names_;  // stable references while handlers run
  std::unordered_map<std::string, int> ids_;
  std::vector<std::vector<int>> targets_;
  std::vector<char> targets_valid_;  // per channel: targets_ is up to date (char: read per delivery)
  std::vector<Entry> queue_;  // entries [head_, count_) wait; their buffers are reused
  std::size_t head_ = 0, count_ = 0;
  bool draining_ = false;
  int64_t published_ = 0;
};

}  // namespace nimble::transport
