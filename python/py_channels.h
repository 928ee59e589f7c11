#pragma once
/// Every message of a flight, by channel, as columns built in C++ while it flies, and handed to
/// Python as numpy arrays in read_log's layout (python/nimble_rig/log.py): channel -> field ->
/// array, one row per message.

#include <pybind11/pybind11.h>

#include <condition_variable>
#include <cstdint>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace nimble::python {

/// One field of a channel over its messages, as read_log lays it out: a number per message, a
/// fixed-size row per message, or a Python object per message (strings, variable-length arrays).
struct Column {
  enum Kind { kFloat, kInt, kObject } kind = kFloat;
  std::size_t width = 1;  ///< values per message of a fixed-size numeric field (1: a scalar)
  bool row = false;       ///< a fixed-size array (even of size 1): a 2-D array
  std::vector<double> f;
  std::vector<std::int64_t> i;
  std::vector<std::vector<double>> fo;       ///< variable-length numeric arrays
  std::vector<std::vector<std::string>> so;  ///< strings and arrays of strings
  bool strings = false;
  bool scalar_string = false;  ///< a string field (not an array of strings)
};

/// Every field of every message of one channel, in .lcm order.
struct ChannelColumns {
  std::vector<std::string> names;
  std::vector<Column> columns;
  std::size_t messages = 0;
};

/// Every message of a run, by channel, decoded as its channel's type (contract/channels.h).
/// add() is called by the flight (no Python, no GIL): it copies the message's bytes into a batch;
/// full batches are decoded into columns by a thread of the collector's own, so that on a machine
/// with a second core the decoding costs the flight little. channels() waits for the last batch.
class ChannelCollector {
 public:
  ChannelCollector();
  ~ChannelCollector();
  ChannelCollector(const ChannelCollector&) = delete;
  ChannelCollector& operator=(const ChannelCollector&) = delete;

  void add(const std::string& channel, const void* data, int size);
  /// Every column, once every message added has been decoded.
  std::map<std::string, ChannelColumns>& channels();

  using Decode = void (*)(const void* data, int size, ChannelColumns& into);
  /// Messages of one batch: where each one's bytes are and which channel it is.
  struct Batch {
    std::vector<unsigned char> bytes;
    struct Item {
      Decode decode;
      ChannelColumns* columns;
      std::size_t offset;
      int size;
    };
    std::vector<Item> items;
  };

 private:
  void hand_over();
  void decode_batches();

  struct Sink {
    Decode decode = nullptr;  ///< nullptr: not a channel of the contract
    ChannelColumns* columns = nullptr;
  };
  std::map<std::string, Sink> sinks_;               ///< by channel, made at its first message
  std::map<std::string, ChannelColumns> channels_;  ///< (a node's columns stay where they are)
  std::size_t pending_batches_ = 0;                 ///< handed over, not yet decoded
  std::condition_variable idle_;
  Batch filling_;
  std::vector<Batch> queue_;
  bool done_ = false;
  std::mutex mutex_;
  std::condition_variable wake_;
  std::thread worker_;
};

/// channel -> field -> numpy array (read_log's layout; strings as numpy unicode arrays); the
/// numeric columns move into their arrays, uncopied. Called with the GIL held, once.
pybind11::dict channels_dict(ChannelCollector& collector);

}  // namespace nimble::python
