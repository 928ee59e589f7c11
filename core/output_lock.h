#pragma once
/// One writer per output. A log, an MCAP file, a campaign directory: each is taken with an
/// exclusive advisory lock (flock(2)) on the file or directory itself before anything is written,
/// so a second writer of the same output is refused at once, naming the path and, where the
/// kernel can tell (/proc/locks), the process that holds it. The lock dies with its holder: a
/// killed run never blocks the next one, and there is no lock file to go stale.
///
/// A file is taken without truncating it: what the holder wrote is untouched by the refused one.
/// The lock belongs to the open file, so it is also held by children forked (not exec'd) from the
/// holder, such as the campaigns' workers, until they end.

#include <cerrno>
#include <cstdint>
#include <optional>
#include <string>
#include <sys/types.h>

#include "core/output_file.h"

namespace nimble {

/// The output is held by another writer (error_number() is EWOULDBLOCK).
class OutputBusy : public OutputError {
 public:
  OutputBusy(const std::string& what, int holder_pid) : OutputError(what, EWOULDBLOCK, -1), holder_pid_(holder_pid) {}
  /// The holder's process id (-1: the kernel did not tell).
  int holder_pid() const { return holder_pid_; }

 private:
  int holder_pid_;
};

/// Who holds a lock on a file: its process id and command line.
struct LockHolder {
  int pid = -1;
  std::string command;  ///< the holder's command line, arguments separated by spaces ("" if unknown)
};

/// The holder of an flock(2) lock on the file (device, inode), from /proc/locks; nullopt if there
/// is none or it cannot be told.
std::optional<LockHolder> lock_holder(dev_t device, ino_t inode);

/// An output taken by this process. Move-only; the lock is released when it goes.
class OutputLock {
 public:
  OutputLock() = default;
  ~OutputLock();
  OutputLock(OutputLock&& other) noexcept;
  OutputLock& operator=(OutputLock&& other) noexcept;
  OutputLock(const OutputLock&) = delete;
  OutputLock& operator=(const OutputLock&) = delete;

  /// Takes the file `path` (created empty if missing, its parent directories too; never
  /// truncated). `what` names the output in messages ("the log", "the MCAP file").
  /// @throws OutputBusy "WHAT PATH is being written by another process (pid N: COMMAND); one
  ///         writer per file: wait for it to end or write elsewhere" if it is held,
  ///         OutputError if it cannot be opened (naming the path and the reason).
  static OutputLock file(const std::string& path, const std::string& what = "the file");
  /// Takes the directory `dir` (created if missing), as file() does.
  static OutputLock directory(const std::string& dir, const std::string& what = "the directory");

  bool held() const { return fd_ >= 0; }
  const std::string& path() const { return path_; }
  /// Releases the lock now.
  void release();

 private:
  OutputLock(int fd, std::string path, dev_t device, ino_t inode);

  int fd_ = -1;
  std::string path_;
  dev_t device_ = 0;
  ino_t inode_ = 0;
};

/// Whether the file open at `fd` is one this process holds through an OutputLock: a writer of
/// this process opening it again (the recorder of a run whose log the run took) goes on under
/// that lock instead of being refused by it.
bool held_by_this_process(int fd);

/// Takes the lock on the open file `fd` (named `path` in messages) for the life of the descriptor,
/// unless this process holds it through an OutputLock already.
/// @throws OutputBusy naming `what` and `path` if another writer holds it.
void lock_open_output(int fd, const std::string& path, const std::string& what);

}  // namespace nimble
