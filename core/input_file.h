#pragma once
/// Input files bounded before they are read.
///
/// Every file the rig reads (a flight record, an LCM log, a scenario and its `base:` files, a
/// model, vehicle, sensing, controller or manoeuvre file, a campaign file or manifest, a file of
/// the web root) is checked here before its first byte is read: it must exist, be a regular file
/// (a FIFO, a device such as /dev/zero, a socket or a directory is refused) and be no larger than
/// the bound of its kind (input_bound()). A file is read whole only through read_input_file(),
/// which checks the descriptor it opened (so a file swapped for a FIFO after the check does not
/// hang it), reads at most the bound (a file that grows, or a /proc file that states no size, is
/// refused there) and names a failed read (/proc/self/mem: an I/O error) with the file.
///
/// The bounds (docs/tool.md, "Input files"):
///  - a configuration file (YAML): 4 MB;
///  - a flight record (CSV): kMaxRecordSamples rows of at most kMaxRecordLineBytes, 512 MB;
///  - an LCM log: kMaxLcmLogBytes, 2.0 GB;
///  - a campaign file (a manifest, a result or run report, JSON): 64 MB;
///  - a file of the web root (rig view --web): 16 MB;
///  - a program whose digest a campaign records (the rig itself): 1.0 GB.

#include <cstdint>
#include <stdexcept>
#include <string>

namespace nimble {

/// What a file is read as; each kind has its size bound.
enum class InputKind { kConfig, kRecord, kLcmLog, kCampaign, kWebFile, kProgram };

/// The most samples (rows) a flight record may hold: over 30 minutes at the IMU's 512 Hz.
inline constexpr std::uint64_t kMaxRecordSamples = 1'000'000;
/// The longest row of a flight record: every channel (t and 16 more) at 17 significant digits
/// with sign and exponent takes under 450 bytes.
inline constexpr std::uint64_t kMaxRecordLineBytes = 512;
/// The largest LCM log the rig reads: a run writes about 1 MB per simulated second (docs/campaigns.md),
/// so over half an hour of flight.
inline constexpr std::uint64_t kMaxLcmLogBytes = 2'000'000'000;

/// A kind's name in messages ("an LCM log") and its bound in bytes.
struct InputBound {
  const char* what;
  std::uint64_t max_bytes;
};

/// The bound of `kind`.
const InputBound& input_bound(InputKind kind);

/// A byte count for people: "312 bytes", "5.2 GB" (decimal units, one decimal).
std::string byte_size_text(std::uint64_t bytes);

/// An input file refused before (or while) it is read: the file and what is wrong with it.
/// what() is "FILE PROBLEM" ("/dev/zero is not a regular file (a character device)").
class InputFileError : public std::runtime_error {
 public:
  InputFileError(std::string file, std::string problem);
  const std::string& file() const { return file_; }
  /// What is wrong, without the file: "file not found", "is a directory, not a file", "is not a
  /// regular file (a FIFO)", "is 5.2 GB, above the 2.0 GB bound for an LCM log", "cannot be read:
  /// Input/output error".
  const std::string& problem() const { return problem_; }

 private:
  std::string file_;
  std::string problem_;
};

/// Checks `file` (following symbolic links) without opening it: it exists, is a regular file
/// and is within the bound of `kind`. @returns its size. @throws InputFileError.
std::uint64_t check_input_file(const std::string& file, InputKind kind);

/// Reads the whole of `file`, checked as check_input_file() but on the descriptor it opened
/// (O_NONBLOCK: opening a FIFO does not wait for a writer), at most the bound of `kind`.
/// @throws InputFileError naming the file and the problem.
std::string read_input_file(const std::string& file, InputKind kind);

/// read_input_file() on a descriptor the caller opened (and closes): fstat, then at most the
/// bound. `file` names it in errors. @throws InputFileError.
std::string read_input_descriptor(int fd, const std::string& file, InputKind kind);

}  // namespace nimble
