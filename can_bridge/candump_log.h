#pragma once
/// candump log format ("candump -L"): the input format of canplayer and log2asc.
///
/// One frame per line: `(SECONDS.MICROSECONDS) INTERFACE FRAME`, e.g.
/// `(1700000000.123456) vcan0 101#10272823881330A7`. FRAME is a 3-digit hex identifier for
/// standard frames, 8 digits for extended and error frames (the latter with CAN_ERR_FLAG, as
/// candump prints them), `#`, then the data bytes as upper-case hex; remote frames are `ID#R`.
/// CAN FD frames are `ID##F` followed by the data: F is one hex digit, the frame's flags
/// (CANFD_BRS 1, CANFD_ESI 2, CANFD_FDF 4), e.g. `(1700000000.123456) vcan1 101##11027282388133071`
/// for a 0x101 frame of 8 bytes with bit rate switch. canplayer replays these on an interface with
/// the CAN FD MTU (72).

#include <linux/can.h>

#include <cstdint>
#include <optional>
#include <string>

#include "core/output_file.h"

namespace nimble::can {

/// One line of a candump log, without the newline. `time_ns`: CLOCK_REALTIME [ns].
std::string format_candump_line(const can_frame& frame, int64_t time_ns, const std::string& interface);
/// The same for a CAN FD frame (`ID##F...`).
std::string format_candump_line(const canfd_frame& frame, int64_t time_ns, const std::string& interface);

/// One parsed candump log line.
struct CandumpRecord {
  int64_t time_ns = 0;    ///< timestamp [ns] (microsecond resolution)
  std::string interface;  ///< interface name as written
  /// The frame. For CAN FD lines: identifier, length and data if the length is at most 8
  /// (so that decoders take it as it is), else the identifier only with length 0.
  can_frame frame{};
  bool is_fd = false;      ///< a CAN FD line (`ID##F...`)
  canfd_frame fd_frame{};  ///< the CAN FD frame with its flags (is_fd only)
};

/// Parses one candump log line: classical frames, remote frames, error frames and CAN FD frames
/// (up to 64 data bytes). nullopt for anything else. Never throws.
std::optional<CandumpRecord> parse_candump_line(const std::string& line);

/// Appends frames to a candump log file that canplayer can replay.
class CandumpWriter {
 public:
  /// Creates or truncates `path`.
  /// @throws std::runtime_error naming the path and errno if it cannot be opened.
  explicit CandumpWriter(const std::string& path);
  ~CandumpWriter();
  CandumpWriter(const CandumpWriter&) = delete;
  CandumpWriter& operator=(const CandumpWriter&) = delete;

  /// Writes one line; false on an I/O error (the log then keeps its whole lines before it and
  /// takes no more: failure() says why). Never throws.
  bool write(const can_frame& frame, int64_t time_ns, const std::string& interface);
  /// Writes one CAN FD line; as write().
  bool write(const canfd_frame& frame, int64_t time_ns, const std::string& interface);
  /// Writes buffered lines to the file; false on an I/O error.
  bool flush();

  /// Lines accepted so far (after a failure: those in the file).
  uint64_t lines_written() const;
  /// "" or why the log could not be written ("candump log F: write failed at byte N: reason").
  const std::string& failure() const { return failure_; }
  /// The log file's path.
  const std::string& path() const { return path_; }

 private:
  bool write_line(std::string line);

  std::string path_;
  OutputFile file_;
  uint64_t lines_ = 0;
  std::string failure_;
};

}  // namespace nimble::can
