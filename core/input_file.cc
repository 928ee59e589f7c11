#include "core/input_file.h"

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <utility>

#include <fcntl.h>
#include <sys/stat.h>
#include <unistd.h>

namespace nimble {
namespace {

const InputBound kConfigBound{"a configuration file", 4'000'000};
const InputBound kRecordBound{"a flight record", kMaxRecordSamples* kMaxRecordLineBytes};
const InputBound kLcmLogBound{"an LCM log", kMaxLcmLogBytes};
const InputBound kCampaignBound{"a campaign file", 64'000'000};
const InputBound kWebFileBound{"a file of the web root", 16'000'000};
const InputBound kProgramBound{"a program", 1'000'000'000};

/// What a file that is not a regular file is, for the message.
std::string file_type_text(mode_t mode) {
  if (S_ISFIFO(mode)) return "a FIFO";
  if (S_ISCHR(mode)) return "a character device";
  if (S_ISBLK(mode)) return "a block device";
  if (S_ISSOCK(mode)) return "a socket";
  if (S_ISLNK(mode)) return "a symbolic link";
  return "not a file";
}

/// Refuses what `st` says is no regular file or is above the bound.
void check_stat(const struct stat& st, const std::string& file, InputKind kind) {
  if (S_ISDIR(st.st_mode)) throw InputFileError(file, "is a directory, not a file");
  if (!S_ISREG(st.st_mode)) throw InputFileError(file, "is not a regular file (" + file_type_text(st.st_mode) + ")");
  const InputBound& bound = input_bound(kind);
  const auto size = static_cast<std::uint64_t>(st.st_size);
  if (size > bound.max_bytes) {
    throw InputFileError(file, "is " + byte_size_text(size) + ", above the " + byte_size_text(bound.max_bytes) +
                                   " bound for " + bound.what);
  }
}

std::string errno_text(int error_number) { return std::strerror(error_number); }

}  // namespace

const InputBound& input_bound(InputKind kind) {
  switch (kind) {
    case InputKind::kConfig: return kConfigBound;
    case InputKind::kRecord: return kRecordBound;
    case InputKind::kLcmLog: return kLcmLogBound;
    case InputKind::kCampaign: return kCampaignBound;
    case InputKind::kWebFile: return kWebFileBound;
    case InputKind::kProgram: return kProgramBound;
  }
  return kConfigBound;
}

std::string byte_size_text(std::uint64_t bytes) {
  if (bytes < 1000) return std::to_string(bytes) + (bytes == 1 ? " byte" : " bytes");
  const char* units[] = {"kB", "MB", "GB", "TB", "PB", "EB"};
  double value = static_cast<double>(bytes) / 1000.0;
  int unit = 0;
  while (value >= 999.95 && unit < 5) {
    value /= 1000.0;
    ++unit;
  }
  char text[32];
  std::snprintf(text, sizeof text, "%.1f %s", value, units[unit]);
  return text;
}

InputFileError::InputFileError(std::string file, std::string problem)
    : std::runtime_error(file + " " + problem), file_(std::move(file)), problem_(std::move(problem)) {}

std::uint64_t check_input_file(const std::string& file, InputKind kind) {
  struct stat st {};
  if (::stat(file.c_str(), &st) != 0) {
    const int e = errno;
    throw InputFileError(file, e == ENOENT ? "file not found" : "cannot be read: " + errno_text(e));
  }
  check_stat(st, file, kind);
  return static_cast<std::uint64_t>(st.st_size);
}

std::string read_input_descriptor(int fd, const std::string& file, InputKind kind) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) throw InputFileError(file, "cannot be read: " + errno_text(errno));
  check_stat(st, file, kind);
  const std::uint64_t max = input_bound(kind).max_bytes;
  std::string text;
  text.reserve(static_cast<std::size_t>(st.st_size));
  char buffer[64 * 1024];
  for (;;) {
    const ssize_t n = ::read(fd, buffer, sizeof buffer);
    if (n < 0) {
      if (errno == EINTR) continue;
      throw InputFileError(file,
                           "cannot be read: " + errno_text(errno) + " (at byte " + std::to_string(text.size()) + ")");
    }
    if (n == 0) break;
    text.append(buffer, static_cast<std::size_t>(n));
    if (text.size() > max) {
      const InputBound& bound = input_bound(kind);
      throw InputFileError(file,
                           "grew past the " + byte_size_text(max) + " bound for " + bound.what + " while it was read");
    }
  }
  return text;
}

std::string read_input_file(const std::string& file, InputKind kind) {
  const int fd = ::open(file.c_str(), O_RDONLY | O_NONBLOCK | O_NOCTTY | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    throw InputFileError(file, e == ENOENT ? "file not found" : "cannot be read: " + errno_text(e));
  }
  try {
    std::string text = read_input_descriptor(fd, file, kind);
    ::close(fd);
    return text;
  } catch (...) {
    ::close(fd);
    throw;
  }
}

}  // namespace nimble
