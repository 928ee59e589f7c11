#pragma once
/// Every message of a flight, by channel, as columns built in C++ while it flies, and handed to
/// Python as numpy arrays in read_log's layout (python/nimble_rig/log.py): channel -> field ->
/// array, one row per message.

#include <pybind11/pybind11.h>

#include <cstdint>
#include <map>
#include <string>
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
  std::vector<std::vector<double>> fo;        ///< variable-length numeric arrays
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
/// add() needs no Python: it runs while the flight flies without the GIL.
class ChannelCollector {
 public:
  void add(const std::string& channel, const void* data, int size);
  const std::map<std::string, ChannelColumns>& channels() const { return channels_; }

 private:
  std::map<std::string, ChannelColumns> channels_;
};

/// channel -> field -> numpy array (read_log's layout); called with the GIL held.
pybind11::dict channels_dict(const ChannelCollector& collector);

}  // namespace nimble::python
