#include "core/output_file.h"

#include "core/output_lock.h"

#include <fcntl.h>
#include <sys/stat.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cerrno>
#include <cinttypes>
#include <cstdio>
#include <cstring>
#include <filesystem>

namespace nimble {

namespace {

namespace fs = std::filesystem;

std::string reason(int error_number) { return error_number != 0 ? std::strerror(error_number) : "unknown error"; }

/// Writes all of `size` bytes at the descriptor's offset; returns the bytes written and sets
/// `error_number` when fewer were.
std::size_t write_all(int fd, const char* data, std::size_t size, int* error_number) {
  std::size_t done = 0;
  *error_number = 0;
  while (done < size) {
    const ssize_t k = ::write(fd, data + done, size - done);
    if (k < 0) {
      if (errno == EINTR) continue;
      *error_number = errno;
      break;
    }
    if (k == 0) {
      *error_number = EIO;
      break;
    }
    done += static_cast<std::size_t>(k);
  }
  return done;
}

void sync_directory_of(const std::string& file) {
  const fs::path dir = fs::path(file).has_parent_path() ? fs::path(file).parent_path() : fs::path(".");
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) return;
  ::fsync(fd);  // the rename is durable; a directory that cannot be synced (some filesystems) is no data lost
  ::close(fd);
}

}  // namespace

void write_file(const std::string& file, std::string_view text) {
  struct stat st {};
  const bool in_place = ::stat(file.c_str(), &st) == 0 && !S_ISREG(st.st_mode);
  const std::string target =
      in_place ? file : file + "." + host_name() + "." + std::to_string(::getpid()) + kPartialSuffix;
  const int fd = in_place ? ::open(target.c_str(), O_WRONLY | O_CLOEXEC)
                          : ::open(target.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int e = errno;
    throw OutputError("cannot write " + file + ": " + reason(e), e, -1);
  }
  const auto give_up = [&](const std::string& what, int e, int64_t at) {
    ::close(fd);
    if (!in_place) ::unlink(target.c_str());
    throw OutputError("cannot write " + file + ": " + what + reason(e), e, at);
  };
  int e = 0;
  const std::size_t done = write_all(fd, text.data(), text.size(), &e);
  if (done != text.size()) {
    give_up("write failed at byte " + std::to_string(done) + " of " + std::to_string(text.size()) + ": ", e,
            static_cast<int64_t>(done));
  }
  if (!in_place && ::fsync(fd) != 0) give_up("fsync failed: ", errno, -1);
  if (::close(fd) != 0) {
    e = errno;
    if (!in_place) ::unlink(target.c_str());
    throw OutputError("cannot write " + file + ": close failed: " + reason(e), e, -1);
  }
  if (in_place) return;
  if (::rename(target.c_str(), file.c_str()) != 0) {
    e = errno;
    ::unlink(target.c_str());
    throw OutputError("cannot write " + file + ": rename of " + target + " failed: " + reason(e), e, -1);
  }
  sync_directory_of(file);
}

void append_to_file(const std::string& file, std::string_view text) {
  const int fd = ::open(file.c_str(), O_WRONLY | O_CREAT | O_APPEND | O_CLOEXEC, 0666);
  if (fd < 0) {
    const int e = errno;
    throw OutputError("cannot append to " + file + ": " + reason(e), e, -1);
  }
  int e = 0;
  const std::size_t done = write_all(fd, text.data(), text.size(), &e);
  if (done == text.size() && ::fsync(fd) != 0 && errno != EINVAL) e = errno;
  if (::close(fd) != 0 && e == 0) e = errno;
  if (done != text.size() || e != 0) {
    throw OutputError("cannot append to " + file + ": " + reason(e) + " (" + std::to_string(done) + " of " +
                          std::to_string(text.size()) + " bytes written)",
                      e, -1);
  }
}

OutputFile::OutputFile(const std::string& file, std::size_t buffer_bytes, const std::string& what)
    : file_(file), capacity_(buffer_bytes > 0 ? buffer_bytes : 1) {
  // Not O_TRUNC: another writer's bytes are cut only once the file is ours.
  fd_ = ::open(file.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0666);
  if (fd_ < 0) {
    const int e = errno;
    throw OutputError("cannot open " + file + " for writing: " + reason(e), e, -1);
  }
  try {
    lock_open_output(fd_, file, what);
  } catch (...) {
    ::close(fd_);
    fd_ = -1;
    throw;
  }
  struct stat st {};
  if (::fstat(fd_, &st) == 0 && S_ISREG(st.st_mode) && ::ftruncate(fd_, 0) != 0) {
    const int e = errno;
    ::close(fd_);
    fd_ = -1;
    throw OutputError("cannot truncate " + file + " for writing: " + reason(e), e, -1);
  }
  buffer_.reserve(capacity_);
}

OutputFile::~OutputFile() {
  if (fd_ < 0) return;
  if (!failed_) {
    try {
      write_buffer();
    } catch (const OutputError&) {
      // cut back to its last whole record by write_buffer(); the owner did not ask to know
    }
  }
  if (fd_ >= 0) ::close(fd_);
}

void OutputFile::fail(const std::string& what, int error_number, int64_t at) {
  failed_ = true;
  buffer_.clear();
  record_ends_.clear();
  std::string cut;
  if (fd_ >= 0 && written_ != whole_end_) {
    if (::ftruncate(fd_, whole_end_) == 0) {
      written_ = whole_end_;
    } else {
      cut = "; cutting it back to its last whole record failed too: " + reason(errno);
    }
  }
  failure_ = file_ + ": " + what + cut;
  throw OutputError(failure_, error_number, at);
}

void OutputFile::write_buffer() {
  if (failed_) throw OutputError(failure_, 0, written_);
  if (buffer_.empty()) return;
  int e = 0;
  const std::size_t done = write_all(fd_, buffer_.data(), buffer_.size(), &e);
  for (const std::size_t end : record_ends_) {
    if (end > done) break;
    whole_end_ = written_ + static_cast<int64_t>(end);
    ++records_written_;
  }
  const int64_t failed_at = written_ + static_cast<int64_t>(done);
  written_ = failed_at;
  if (done != buffer_.size())
    fail("write failed at byte " + std::to_string(failed_at) + ": " + reason(e), e, failed_at);
  buffer_.clear();
  record_ends_.clear();
}

void OutputFile::append(const void* data, std::size_t size) {
  if (failed_) throw OutputError(failure_, 0, written_);
  if (max_bytes_ > 0 && this->size() + static_cast<int64_t>(size) > max_bytes_) {
    // Keep the whole records before this one, then refuse.
    const int64_t at = this->size();
    buffer_.resize(record_ends_.empty() ? 0 : record_ends_.back());
    write_buffer();  // a failure here is named as such
    fail("the file reached its limit of " + std::to_string(max_bytes_) + " bytes at byte " + std::to_string(at), 0, at);
  }
  if (!buffer_.empty() && buffer_.size() + size > capacity_) write_buffer();
  const char* p = static_cast<const char*>(data);
  buffer_.insert(buffer_.end(), p, p + size);
  if (buffer_.size() >= capacity_) write_buffer();
}

void OutputFile::end_record() {
  if (buffer_.empty()) {
    // The record's bytes all reached the file already.
    if (!failed_) {
      whole_end_ = written_;
      ++records_written_;
    }
    return;
  }
  record_ends_.push_back(buffer_.size());
}

void OutputFile::flush() { write_buffer(); }

void OutputFile::close() {
  if (fd_ < 0) return;
  write_buffer();
  if (::fsync(fd_) != 0 && errno != EINVAL && errno != EROFS) {
    const int e = errno;
    fail("fsync failed: " + reason(e), e, written_);
  }
  const int rc = ::close(fd_);
  const int e = errno;
  fd_ = -1;
  if (rc != 0) {
    failed_ = true;
    failure_ = file_ + ": close failed: " + reason(e);
    throw OutputError(failure_, e, written_);
  }
}

int64_t free_bytes_at(const std::string& path) {
  fs::path p = fs::absolute(path);
  std::error_code ec;
  while (!p.empty() && !fs::exists(p, ec)) {
    if (p == p.parent_path()) break;
    p = p.parent_path();
  }
  struct statvfs vfs {};
  if (::statvfs(p.c_str(), &vfs) != 0) return -1;
  return static_cast<int64_t>(vfs.f_bavail) * static_cast<int64_t>(vfs.f_frsize);
}

std::string host_name() {
  char name[256] = {};
  if (::gethostname(name, sizeof name - 1) != 0) return "unknown";
  return name;
}

std::string human_bytes(int64_t bytes) {
  char buf[32];
  const double b = static_cast<double>(bytes);
  if (bytes < 1000)
    std::snprintf(buf, sizeof buf, "%" PRId64 " B", bytes);
  else if (bytes < 1000000)
    std::snprintf(buf, sizeof buf, "%.1f kB", b / 1e3);
  else if (bytes < 1000000000)
    std::snprintf(buf, sizeof buf, "%.1f MB", b / 1e6);
  else
    std::snprintf(buf, sizeof buf, "%.2f GB", b / 1e9);
  return buf;
}

}  // namespace nimble
