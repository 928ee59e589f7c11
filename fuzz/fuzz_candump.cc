// Fuzz target: the candump log reader (can_bridge/candump_log.h, parse_candump_line), line by
// line over the input. It never throws; a line it takes must come back the same after writing it
// again with format_candump_line (parse(format(parse(line))) == parse(line)).

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

#include "can_bridge/candump_log.h"
#include "fuzz/fuzz_support.h"

using namespace nimble::can;
using nimble::fuzz::require;

namespace {

bool same(const CandumpRecord& a, const CandumpRecord& b) {
  if (a.time_ns != b.time_ns || a.interface != b.interface || a.is_fd != b.is_fd) return false;
  if (a.frame.can_id != b.frame.can_id || a.frame.len != b.frame.len) return false;
  if (std::memcmp(a.frame.data, b.frame.data, a.frame.len <= CAN_MAX_DLEN ? a.frame.len : CAN_MAX_DLEN) != 0)
    return false;
  if (!a.is_fd) return true;
  return a.fd_frame.can_id == b.fd_frame.can_id && a.fd_frame.len == b.fd_frame.len &&
         a.fd_frame.flags == b.fd_frame.flags &&
         std::memcmp(a.fd_frame.data, b.fd_frame.data,
                     a.fd_frame.len <= CANFD_MAX_DLEN ? a.fd_frame.len : CANFD_MAX_DLEN) == 0;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  std::size_t start = 0;
  while (start <= text.size()) {
    std::size_t end = text.find('\n', start);
    if (end == std::string::npos) end = text.size();
    const std::string line = text.substr(start, end - start);
    start = end + 1;
    const auto record = parse_candump_line(line);
    if (!record) continue;
    require(record->frame.len <= CAN_MAX_DLEN, "parsed frame longer than 8 bytes");
    require(!record->is_fd || record->fd_frame.len <= CANFD_MAX_DLEN, "parsed CAN FD frame longer than 64 bytes");
    const std::string again = record->is_fd ? format_candump_line(record->fd_frame, record->time_ns, record->interface)
                                            : format_candump_line(record->frame, record->time_ns, record->interface);
    const auto reparsed = parse_candump_line(again);
    require(reparsed.has_value(),
            "the line written for a parsed line does not parse: '" + again + "' from '" + line + "'");
    require(same(*record, *reparsed),
            "a parsed line changes when written and parsed again: '" + line + "' -> '" + again + "'");
  }
  return 0;
}
