#include "core/output_lock.h"

#include <fcntl.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <sys/sysmacros.h>
#include <unistd.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <mutex>
#include <set>
#include <sstream>
#include <utility>

namespace nimble {

namespace {

namespace fs = std::filesystem;

/// The (device, inode) of every output this process holds through an OutputLock.
std::mutex& held_mutex() {
  static std::mutex m;
  return m;
}
std::set<std::pair<dev_t, ino_t>>& held_set() {
  static std::set<std::pair<dev_t, ino_t>> s;
  return s;
}

std::string lock_reason(int e) { return e != 0 ? std::strerror(e) : "unknown error"; }

/// The command line of process `pid`, arguments joined by spaces ("" if it cannot be read).
std::string command_of(int pid) {
  std::ifstream in("/proc/" + std::to_string(pid) + "/cmdline", std::ios::binary);
  std::string s((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  while (!s.empty() && s.back() == '\0') s.pop_back();
  for (char& c : s) {
    if (c == '\0') c = ' ';
  }
  constexpr std::size_t kMax = 200;
  if (s.size() > kMax) s = s.substr(0, kMax) + "...";
  return s;
}

[[noreturn]] void refuse(const std::string& what, const std::string& path, dev_t device, ino_t inode,
                         const char* kind) {
  const std::optional<LockHolder> holder = lock_holder(device, inode);
  std::string by = "another process";
  if (holder) {
    by = "another process (pid " + std::to_string(holder->pid) +
         (holder->command.empty() ? std::string() : ": " + holder->command) + ")";
  }
  throw OutputBusy(what + " " + path + " is being written by " + by + "; one writer per " + kind +
                       ": wait for it to end or write elsewhere",
                   holder ? holder->pid : -1);
}

}  // namespace

std::optional<LockHolder> lock_holder(dev_t device, ino_t inode) {
  std::ifstream in("/proc/locks");
  std::string line;
  // "1: FLOCK  ADVISORY  WRITE 2519 00:1e:1966 0 EOF": major and minor in hex, the inode in decimal.
  // A waiter's line has "->" after the number; only holders count.
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    std::string number, type, mode, access, pid, where;
    if (!(fields >> number >> type)) continue;
    if (type == "->") continue;
    if (type != "FLOCK" || !(fields >> mode >> access >> pid >> where)) continue;
    unsigned major_id = 0, minor_id = 0;
    unsigned long long ino = 0;
    if (std::sscanf(where.c_str(), "%x:%x:%llu", &major_id, &minor_id, &ino) != 3) continue;
    if (ino != static_cast<unsigned long long>(inode) || major_id != major(device) || minor_id != minor(device))
      continue;
    const int p = std::atoi(pid.c_str());
    if (p <= 0) continue;
    return LockHolder{p, command_of(p)};
  }
  return std::nullopt;
}

OutputLock::~OutputLock() { release(); }

OutputLock::OutputLock(OutputLock&& other) noexcept
    : fd_(std::exchange(other.fd_, -1)), path_(std::move(other.path_)), device_(other.device_), inode_(other.inode_) {}

OutputLock& OutputLock::operator=(OutputLock&& other) noexcept {
  if (this != &other) {
    release();
    fd_ = std::exchange(other.fd_, -1);
    path_ = std::move(other.path_);
    device_ = other.device_;
    inode_ = other.inode_;
  }
  return *this;
}

void OutputLock::release() {
  if (fd_ < 0) return;
  {
    std::lock_guard<std::mutex> g(held_mutex());
    held_set().erase({device_, inode_});
  }
  ::close(fd_);  // the flock goes with the last descriptor of the open file
  fd_ = -1;
}

namespace {

/// Locks the open `fd` (closed on failure) and returns its (device, inode).
/// @throws OutputBusy if another writer holds it, OutputError on any other failure.
struct stat lock_or_close(int fd, const std::string& path, const std::string& what, const char* kind) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) {
    const int e = errno;
    ::close(fd);
    throw OutputError("cannot take " + what + " " + path + ": " + lock_reason(e), e, -1);
  }
  if (std::string(kind) == "file" && !S_ISREG(st.st_mode)) {
    ::close(fd);
    throw OutputError(what + " " + path + " is not a regular file", EINVAL, -1);
  }
  while (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EINTR) continue;
    const int e = errno;
    ::close(fd);
    if (e == EWOULDBLOCK) refuse(what, path, st.st_dev, st.st_ino, kind);
    throw OutputError("cannot lock " + what + " " + path + ": " + lock_reason(e), e, -1);
  }
  return st;
}

}  // namespace

OutputLock OutputLock::file(const std::string& path, const std::string& what) {
  std::error_code ec;
  if (fs::path(path).has_parent_path()) fs::create_directories(fs::path(path).parent_path(), ec);
  // Never O_TRUNC: the bytes are the holder's until the lock is ours. O_NONBLOCK: a FIFO does not
  // hang the open (it is refused as no regular file).
  const int fd = ::open(path.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC | O_NONBLOCK, 0666);
  if (fd < 0) {
    const int e = errno;
    throw OutputError("cannot open " + what + " " + path + " for writing: " + lock_reason(e), e, -1);
  }
  const struct stat st = lock_or_close(fd, path, what, "file");
  return OutputLock(fd, path, st.st_dev, st.st_ino);
}

OutputLock OutputLock::directory(const std::string& dir, const std::string& what) {
  std::error_code ec;
  fs::create_directories(dir, ec);
  const int fd = ::open(dir.c_str(), O_RDONLY | O_DIRECTORY | O_CLOEXEC);
  if (fd < 0) {
    const int e = errno;
    throw OutputError("cannot open " + what + " " + dir + ": " + lock_reason(e), e, -1);
  }
  const struct stat st = lock_or_close(fd, dir, what, "directory");
  return OutputLock(fd, dir, st.st_dev, st.st_ino);
}

OutputLock::OutputLock(int fd, std::string path, dev_t device, ino_t inode)
    : fd_(fd), path_(std::move(path)), device_(device), inode_(inode) {
  std::lock_guard<std::mutex> g(held_mutex());
  held_set().insert({device_, inode_});
}

bool held_by_this_process(int fd) {
  struct stat st {};
  if (::fstat(fd, &st) != 0) return false;
  std::lock_guard<std::mutex> g(held_mutex());
  return held_set().count({st.st_dev, st.st_ino}) > 0;
}

void lock_open_output(int fd, const std::string& path, const std::string& what) {
  if (held_by_this_process(fd)) return;
  struct stat st {};
  if (::fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) return;  // a FIFO or a device: nothing to share
  while (::flock(fd, LOCK_EX | LOCK_NB) != 0) {
    if (errno == EINTR) continue;
    const int e = errno;
    if (e == EWOULDBLOCK) refuse(what, path, st.st_dev, st.st_ino, "file");
    throw OutputError("cannot lock " + what + " " + path + ": " + lock_reason(e), e, -1);
  }
}

}  // namespace nimble
