#pragma once
/// Output files whose every write is checked: a full disk (ENOSPC), an I/O error (EIO), a file
/// over its size limit (EFBIG, RLIMIT_FSIZE) or a quota (EDQUOT) is an OutputError naming the
/// file, the byte and the system's reason, never a silent loss.
///
/// Two ways to write:
///  - write_file(): a whole file (a report, a model, a result) at once, or not at all. It goes
///    to a temporary file beside the target, is synced and renamed over it, so a failure leaves
///    the target as it was.
///  - OutputFile: a file written in pieces as they come (a log). Records end at end_record();
///    a write that fails cuts the file back to the end of its last whole record, so what is
///    kept reads as a whole file of fewer records.
/// Every descriptor is opened close-on-exec: a child process inherits none of them.

#include <cstddef>
#include <cstdint>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

namespace nimble {

/// A failed open, write, flush, fsync, close or rename of an output file.
class OutputError : public std::runtime_error {
 public:
  OutputError(const std::string& what, int error_number, int64_t offset)
      : std::runtime_error(what), error_number_(error_number), offset_(offset) {}
  /// errno of the failed call (0 if none, e.g. a size limit of the rig's own).
  int error_number() const { return error_number_; }
  /// The byte of the file at which the write failed (-1: not a write).
  int64_t offset() const { return offset_; }

 private:
  int error_number_;
  int64_t offset_;
};

/// The suffix of write_file()'s temporary files (FILE.HOST.PID.partial): what a crash may leave.
inline constexpr const char* kPartialSuffix = ".partial";

/// Writes `text` to `file` whole or not at all: a temporary file in the same directory (named
/// apart per host and process, for directories shared by the nodes of a cluster), every
/// write checked, fsync, rename over `file`, fsync of the directory. A target that exists and is
/// no regular file (a FIFO, /dev/stdout) is written in place instead. On failure the temporary
/// file is removed and `file` is left as it was.
/// @throws OutputError "cannot write FILE: REASON (at byte N of M)".
void write_file(const std::string& file, std::string_view text);

/// Appends `text` to `file` (made if missing), every write checked, then fsync: a line of a
/// journal. @throws OutputError naming the file.
void append_to_file(const std::string& file, std::string_view text);

/// A file written in pieces, buffered, every write checked.
class OutputFile {
 public:
  /// Creates (or truncates) `file` for writing, with a write buffer of `buffer_bytes`. A regular
  /// file is first taken for this writer (core/output_lock.h): while another writer holds it, it
  /// is refused untouched (OutputBusy naming `what`, the file and the holder), unless this process
  /// took it already through an OutputLock.
  /// @throws OutputError naming the file if it cannot be opened, OutputBusy if it is held.
  explicit OutputFile(const std::string& file, std::size_t buffer_bytes = 1u << 20,
                      const std::string& what = "the file");
  /// Closes the file; what is buffered is written, errors are not reported (call close()).
  ~OutputFile();
  OutputFile(const OutputFile&) = delete;
  OutputFile& operator=(const OutputFile&) = delete;

  /// Appends `size` bytes (buffered: they reach the file when the buffer is full or at flush()).
  /// @throws OutputError when a write fails (the file then ends on its last whole record), or
  ///         when the file would pass max_bytes(); the file takes nothing more after either.
  void append(const void* data, std::size_t size);
  /// A whole record ends here.
  void end_record();
  /// Writes what is buffered. @throws OutputError as append().
  void flush();
  /// flush(), fsync, close. @throws OutputError naming the call that failed.
  void close();

  /// Refuse to grow the file past `bytes` (0: no limit): the append that would is an
  /// OutputError and the file ends on its last whole record before it.
  void set_max_bytes(int64_t bytes) { max_bytes_ = bytes; }
  int64_t max_bytes() const { return max_bytes_; }

  const std::string& file() const { return file_; }
  /// Bytes appended so far (written and buffered).
  int64_t size() const { return written_ + static_cast<int64_t>(buffer_.size()); }
  /// Whether a write failed (nothing more is taken).
  bool failed() const { return failed_; }
  /// What the file holds for sure: its bytes and whole records, after a failure those kept
  /// (the file was cut back to them); before, those written so far (not those buffered).
  int64_t kept_bytes() const { return whole_end_; }
  int64_t kept_records() const { return records_written_; }

 private:
  /// Writes the buffer; on failure cuts the file back to its last whole record and throws.
  void write_buffer();
  /// Marks the file failed, cuts it back to its last whole record, throws `what` (after the file's name).
  [[noreturn]] void fail(const std::string& what, int error_number, int64_t at);

  std::string file_;
  int fd_ = -1;
  std::vector<char> buffer_;
  std::size_t capacity_;
  std::vector<std::size_t> record_ends_;  ///< ends of the whole records in buffer_
  int64_t written_ = 0;                   ///< bytes in the file
  int64_t whole_end_ = 0;                 ///< the end of the file's last whole record
  int64_t records_written_ = 0;
  int64_t max_bytes_ = 0;
  bool failed_ = false;
  std::string failure_;
};

/// Free bytes for an unprivileged writer on the filesystem holding `path` (its directory when
/// the file does not exist yet); -1 if it cannot be told.
int64_t free_bytes_at(const std::string& path);

/// This machine's host name ("unknown" if it cannot be told): in write_file()'s temporary names,
/// and where a record says which machine wrote it.
std::string host_name();

/// "12.3 MB" (decimal units), for messages about sizes.
std::string human_bytes(int64_t bytes);

}  // namespace nimble
