#pragma once
/// Reading an LCM log (the event format of lcm-logger, lcm::LogFile and the rig's recorder)
/// without trusting it.
///
/// lcm::LogFile stops at the first event it cannot read and reports a clean end: a log cut in
/// half reads as half a flight. LcmLogReader checks every event header against the file
/// (sync word, lengths, the file's end) and names the damage: the file, the byte offset and
/// the number of the event. With `salvage` it stops there instead and says how much it left.

#include <cstdint>
#include <fstream>
#include <string>
#include <vector>

#include "core/data_error.h"

namespace nimble::lcmlog {

/// One event of an LCM log.
struct LogEventRecord {
  int64_t event_number = 0;  ///< as written in the log
  int64_t timestamp_us = 0;  ///< event time as written (wall clock or simulated time)
  std::string channel;
  std::vector<uint8_t> data;
  int64_t offset = 0;  ///< byte offset of the event in the file
};

class LcmLogReader {
 public:
  /// Opens `file`. `salvage`: at damage, end the log there (see damage()) instead of throwing.
  /// @throws DataError if the file cannot be opened, is no regular file (a FIFO, a device) or is
  ///         above the bound of an LCM log (kMaxLcmLogBytes, core/input_file.h), checked before any
  ///         byte is read, or does not start as an LCM log.
  LcmLogReader(const std::string& file, bool salvage = false);

  /// Reads the next event into `ev`; false at the end of the log (or, salvaging, at damage).
  /// @throws DataError naming the file, the byte offset and the event of the damage (a header
  ///         without the sync word, an implausible length, an event that runs past the end).
  bool next(LogEventRecord* ev);

  /// Salvaging: what was wrong and how much was left unread ("" if the log was whole).
  const std::string& damage() const { return damage_; }
  /// Events read so far.
  int64_t events() const { return events_; }

 private:
  /// At damage found at `offset`: throws, or (salvaging) records it and returns false.
  bool damaged(int64_t offset, const std::string& problem);

  std::string file_;
  bool salvage_;
  std::ifstream in_;
  int64_t size_ = 0;
  int64_t offset_ = 0;
  int64_t events_ = 0;
  std::string damage_;
};

}  // namespace nimble::lcmlog
