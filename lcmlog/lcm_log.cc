#include "lcmlog/lcm_log.h"

#include <filesystem>

#include "core/input_file.h"

namespace nimble::lcmlog {
namespace {

constexpr uint32_t kSync = 0xEDA1DA01;
constexpr int kHeaderBytes = 4 + 8 + 8 + 4 + 4;  // sync, event number, timestamp, channel and data lengths
constexpr int32_t kMaxChannelBytes = 256;        // LCM's own limit is 63

uint64_t big_endian(const unsigned char* p, int n) {
  uint64_t v = 0;
  for (int i = 0; i < n; ++i) v = (v << 8) | p[i];
  return v;
}

}  // namespace

LcmLogReader::LcmLogReader(const std::string& file, bool salvage) : file_(file), salvage_(salvage) {
  std::error_code ec;
  try {
    check_input_file(file, InputKind::kLcmLog);  // no byte is read of a FIFO, a device or a huge file
  } catch (const InputFileError& e) {
    throw DataError(file, -1, -1, "", e.problem());
  }
  in_.open(file, std::ios::binary);
  if (!in_) throw DataError(file, -1, -1, "", "cannot be opened");
  size_ = static_cast<int64_t>(std::filesystem::file_size(file, ec));
  unsigned char sync[4];
  if (!in_.read(reinterpret_cast<char*>(sync), 4) || big_endian(sync, 4) != kSync) {
    throw DataError(file, -1, -1, "", "is not an LCM log (no event sync word at byte 0)");
  }
  in_.seekg(0);
}

bool LcmLogReader::damaged(int64_t offset, const std::string& problem) {
  const std::string where = "damaged at byte " + std::to_string(offset) + " of " + std::to_string(size_) + ", event " +
                            std::to_string(events_ + 1) + " (after " + std::to_string(events_) +
                            " whole events): " + problem;
  if (!salvage_) {
    throw DataError(file_, -1, -1, "",
                    where + "; --salvage reads the events before it and leaves the last " +
                        std::to_string(size_ - offset) + " bytes");
  }
  damage_ = where + "; read the " + std::to_string(events_) + " events before it, left " +
            std::to_string(size_ - offset) + " bytes (" +
            std::to_string(size_ > 0 ? 100 * (size_ - offset) / size_ : 0) + " % of the file)";
  offset_ = size_;
  return false;
}

bool LcmLogReader::next(LogEventRecord* ev) {
  if (offset_ >= size_) return false;
  const int64_t at = offset_;
  if (size_ - at < kHeaderBytes) return damaged(at, "the file ends inside an event header (truncated)");
  unsigned char h[kHeaderBytes];
  in_.seekg(at);
  if (!in_.read(reinterpret_cast<char*>(h), kHeaderBytes)) return damaged(at, "cannot read the event header");
  if (big_endian(h, 4) != kSync) return damaged(at, "no event sync word where an event should start");
  const int64_t number = static_cast<int64_t>(big_endian(h + 4, 8));
  const int64_t timestamp = static_cast<int64_t>(big_endian(h + 12, 8));
  const auto channel_bytes = static_cast<int32_t>(big_endian(h + 20, 4));
  const auto data_bytes = static_cast<int32_t>(big_endian(h + 24, 4));
  if (channel_bytes <= 0 || channel_bytes > kMaxChannelBytes) {
    return damaged(at, "implausible channel name length " + std::to_string(channel_bytes));
  }
  if (data_bytes < 0) return damaged(at, "negative data length " + std::to_string(data_bytes));
  const int64_t end = at + kHeaderBytes + channel_bytes + data_bytes;
  if (end > size_) {
    return damaged(at, "the event needs " + std::to_string(end - at) + " bytes, the file ends after " +
                           std::to_string(size_ - at) + " (truncated)");
  }
  ev->offset = at;
  ev->event_number = number;
  ev->timestamp_us = timestamp;
  ev->channel.resize(static_cast<std::size_t>(channel_bytes));
  ev->data.resize(static_cast<std::size_t>(data_bytes));
  if (!in_.read(ev->channel.data(), channel_bytes) || !in_.read(reinterpret_cast<char*>(ev->data.data()), data_bytes)) {
    return damaged(at, "cannot read the event's channel and data");
  }
  for (const char c : ev->channel) {
    if (static_cast<unsigned char>(c) < 0x20 || static_cast<unsigned char>(c) > 0x7e) {
      return damaged(at, "the channel name is not printable text");
    }
  }
  offset_ = end;
  ++events_;
  return true;
}

}  // namespace nimble::lcmlog
