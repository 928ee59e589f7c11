#include "can_bridge/candump_log.h"

#include <cerrno>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace nimble::can {

namespace {

constexpr char kHex[] = "0123456789ABCDEF";

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  return -1;
}

/// Hex data bytes into `out` (at most `max_len`); optional '.' separators between bytes (cansend
/// syntax) are accepted. The number of bytes, or nullopt.
std::optional<unsigned> parse_data(const std::string& data, uint8_t* out, unsigned max_len) {
  unsigned len = 0;
  for (std::size_t i = 0; i < data.size();) {
    if (data[i] == '.') {
      ++i;
      continue;
    }
    if (i + 1 >= data.size() || len >= max_len) return std::nullopt;
    const int hi = hex_value(data[i]), lo = hex_value(data[i + 1]);
    if (hi < 0 || lo < 0) return std::nullopt;
    out[len++] = static_cast<uint8_t>((hi << 4) | lo);
    i += 2;
  }
  return len;
}

/// "(SECONDS.MICROS) INTERFACE ID" of a line.
std::string line_head(canid_t can_id, int64_t time_ns, const std::string& interface) {
  const int64_t us_total = time_ns / 1000;
  char head[64];
  std::snprintf(head, sizeof head, "(%010lld.%06lld) ", static_cast<long long>(us_total / 1000000),
                static_cast<long long>(us_total % 1000000));
  std::string line = head;
  line += interface;
  line += ' ';
  char id[16];
  if (can_id & CAN_ERR_FLAG) {
    std::snprintf(id, sizeof id, "%08X", can_id & (CAN_ERR_MASK | CAN_ERR_FLAG));
  } else if (can_id & CAN_EFF_FLAG) {
    std::snprintf(id, sizeof id, "%08X", can_id & CAN_EFF_MASK);
  } else {
    std::snprintf(id, sizeof id, "%03X", can_id & CAN_SFF_MASK);
  }
  line += id;
  return line;
}

void append_hex(std::string& line, const uint8_t* data, unsigned len) {
  for (unsigned i = 0; i < len; ++i) {
    line += kHex[data[i] >> 4];
    line += kHex[data[i] & 0x0F];
  }
}

}  // namespace

std::string format_candump_line(const can_frame& frame, int64_t time_ns, const std::string& interface) {
  std::string line = line_head(frame.can_id, time_ns, interface);
  line += '#';
  if ((frame.can_id & CAN_RTR_FLAG) && !(frame.can_id & CAN_ERR_FLAG)) {
    line += 'R';
    if (frame.len > 0 && frame.len <= CAN_MAX_DLEN) line += kHex[frame.len];
    return line;
  }
  append_hex(line, frame.data, frame.len <= CAN_MAX_DLEN ? frame.len : CAN_MAX_DLEN);
  return line;
}

std::string format_candump_line(const canfd_frame& frame, int64_t time_ns, const std::string& interface) {
  std::string line = line_head(frame.can_id, time_ns, interface);
  line += "##";
  line += kHex[frame.flags & 0x0F];
  append_hex(line, frame.data, frame.len <= CANFD_MAX_DLEN ? frame.len : CANFD_MAX_DLEN);
  return line;
}

std::optional<CandumpRecord> parse_candump_line(const std::string& line) {
  CandumpRecord rec;
  std::memset(&rec.frame, 0, sizeof rec.frame);
  // (SECONDS.MICROS)
  if (line.size() < 4 || line[0] != '(') return std::nullopt;
  const auto close = line.find(')');
  const auto dot = line.find('.');
  if (close == std::string::npos || dot == std::string::npos || dot > close) return std::nullopt;
  // The time must fit time_ns: a larger number of seconds (year 2262 on) is not a candump line.
  constexpr long long kMaxSeconds = (std::numeric_limits<int64_t>::max() / 1000 - 999999) / 1000000;
  long long sec = 0, usec = 0;
  for (std::size_t i = 1; i < dot; ++i) {
    if (line[i] < '0' || line[i] > '9') return std::nullopt;
    sec = sec * 10 + (line[i] - '0');
    if (sec > kMaxSeconds) return std::nullopt;
  }
  if (close - dot - 1 != 6) return std::nullopt;
  for (std::size_t i = dot + 1; i < close; ++i) {
    if (line[i] < '0' || line[i] > '9') return std::nullopt;
    usec = usec * 10 + (line[i] - '0');
  }
  rec.time_ns = (sec * 1000000 + usec) * 1000;
  // INTERFACE
  std::size_t pos = close + 1;
  if (pos >= line.size() || line[pos] != ' ') return std::nullopt;
  const auto space = line.find(' ', pos + 1);
  if (space == std::string::npos || space == pos + 1) return std::nullopt;
  rec.interface = line.substr(pos + 1, space - pos - 1);
  // ID#DATA
  std::string text = line.substr(space + 1);
  while (!text.empty() && (text.back() == '\n' || text.back() == '\r' || text.back() == ' ')) text.pop_back();
  const auto hash = text.find('#');
  if (hash == std::string::npos || (hash != 3 && hash != 8)) return std::nullopt;
  const bool fd = text.compare(hash, 2, "##") == 0;
  uint32_t id = 0;
  for (std::size_t i = 0; i < hash; ++i) {
    const int v = hex_value(text[i]);
    if (v < 0) return std::nullopt;
    id = (id << 4) | static_cast<uint32_t>(v);
  }
  if (hash == 3) {
    if (id > CAN_SFF_MASK) return std::nullopt;
  } else if (id & CAN_ERR_FLAG) {
    // An error frame: its class bits and nothing else (candump writes no other flag with it).
    if (id & ~(CAN_ERR_FLAG | CAN_ERR_MASK)) return std::nullopt;
  } else {
    // An extended identifier: 29 bits (no flag bits, which candump never writes).
    if (id > CAN_EFF_MASK) return std::nullopt;
    id |= CAN_EFF_FLAG;
  }
  rec.frame.can_id = id;
  if (fd) {
    // ID##F DATA: F = flags (one hex digit), then up to 64 data bytes.
    if (id & CAN_ERR_FLAG) return std::nullopt;
    if (hash + 2 >= text.size()) return std::nullopt;
    const int flags = hex_value(text[hash + 2]);
    if (flags < 0) return std::nullopt;
    std::memset(&rec.fd_frame, 0, sizeof rec.fd_frame);
    rec.is_fd = true;
    rec.fd_frame.can_id = id;
    rec.fd_frame.flags = static_cast<uint8_t>(flags);
    const auto len = parse_data(text.substr(hash + 3), rec.fd_frame.data, CANFD_MAX_DLEN);
    if (!len) return std::nullopt;
    rec.fd_frame.len = static_cast<uint8_t>(*len);
    if (*len <= CAN_MAX_DLEN) {
      rec.frame.len = static_cast<uint8_t>(*len);
      std::memcpy(rec.frame.data, rec.fd_frame.data, *len);
    }
    return rec;
  }
  std::string data = text.substr(hash + 1);
  if (!data.empty() && (data[0] == 'R' || data[0] == 'r')) {
    if (id & CAN_ERR_FLAG) return std::nullopt;  // an error frame is not a remote frame
    rec.frame.can_id |= CAN_RTR_FLAG;
    if (data.size() == 2 && hex_value(data[1]) >= 0 && hex_value(data[1]) <= CAN_MAX_DLEN) {
      rec.frame.len = static_cast<uint8_t>(hex_value(data[1]));
    } else if (data.size() != 1) {
      return std::nullopt;
    }
    return rec;
  }
  const auto len = parse_data(data, rec.frame.data, CAN_MAX_DLEN);
  if (!len) return std::nullopt;
  rec.frame.len = static_cast<uint8_t>(*len);
  return rec;
}

CandumpWriter::CandumpWriter(const std::string& path) : path_(path), file_(path, 64u << 10, "the candump log") {}

CandumpWriter::~CandumpWriter() = default;

bool CandumpWriter::write(const can_frame& frame, int64_t time_ns, const std::string& interface) {
  return write_line(format_candump_line(frame, time_ns, interface));
}

bool CandumpWriter::write(const canfd_frame& frame, int64_t time_ns, const std::string& interface) {
  return write_line(format_candump_line(frame, time_ns, interface));
}

bool CandumpWriter::write_line(std::string line) {
  if (!failure_.empty()) return false;
  line += '\n';
  try {
    file_.append(line.data(), line.size());
    file_.end_record();
  } catch (const OutputError& e) {
    failure_ = std::string("candump log ") + e.what();
    return false;
  }
  ++lines_;
  return true;
}

bool CandumpWriter::flush() {
  if (!failure_.empty()) return false;
  try {
    file_.flush();
  } catch (const OutputError& e) {
    failure_ = std::string("candump log ") + e.what();
    return false;
  }
  return true;
}

uint64_t CandumpWriter::lines_written() const {
  return failure_.empty() ? lines_ : static_cast<uint64_t>(file_.kept_records());
}

}  // namespace nimble::can
