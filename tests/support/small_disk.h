#pragma once
/// Test support: a small disk for the tests of full-disk handling.
///
/// Where the machine allows (root, or a user namespace), the test process moves into a mount
/// namespace of its own and mounts a tmpfs of the asked size on a fresh directory: a write past
/// it fails with ENOSPC, as on a full disk. Elsewhere the commands the test runs get a file size
/// limit of the same size instead (RLIMIT_FSIZE through prlimit(1)): a write past it fails with
/// EFBIG. Either way the test says which (describe()), so its output names what was tested.

#include <sched.h>
#include <sys/mount.h>
#include <sys/statvfs.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

namespace nimble::test {

class SmallDisk {
 public:
  /// A directory `dir` (made fresh) of `bytes` bytes.
  SmallDisk(const std::string& dir, int64_t bytes) : dir_(dir), bytes_(bytes) {
    std::filesystem::remove_all(dir);
    std::filesystem::create_directories(dir);
    // A mount namespace of this test process alone: the mount is gone when it ends.
    if (::unshare(CLONE_NEWNS) == 0 && ::mount("none", "/", nullptr, MS_REC | MS_PRIVATE, nullptr) == 0) {
      const std::string opts = "size=" + std::to_string(bytes);
      tmpfs_ = ::mount("tmpfs", dir.c_str(), "tmpfs", 0, opts.c_str()) == 0;
    }
  }
  ~SmallDisk() {
    if (tmpfs_) ::umount2(dir_.c_str(), MNT_DETACH);
  }
  SmallDisk(const SmallDisk&) = delete;
  SmallDisk& operator=(const SmallDisk&) = delete;

  const std::string& dir() const { return dir_; }
  /// True: a tmpfs (ENOSPC); false: a file size limit (EFBIG) through command_prefix().
  bool tmpfs() const { return tmpfs_; }
  /// What stands before a command so that it writes on the small disk ("" on a tmpfs).
  std::string command_prefix() const {
    return tmpfs_ ? std::string() : "prlimit --fsize=" + std::to_string(bytes_) + ":" + std::to_string(bytes_) + " ";
  }
  /// The system's text for the error a write past the disk gets.
  std::string error_text() const { return tmpfs_ ? "No space left on device" : "File too large"; }
  std::string describe() const {
    return tmpfs_ ? "a tmpfs of " + std::to_string(bytes_) + " bytes in a private mount namespace (ENOSPC)"
                  : "no mount possible here: a file size limit (RLIMIT_FSIZE) of " + std::to_string(bytes_) +
                        " bytes (EFBIG)";
  }
  /// Fills the disk up to `keep_free` free bytes (a tmpfs only; with a size limit every file
  /// has the whole limit).
  void fill_to(int64_t keep_free) const {
    if (!tmpfs_) return;
    struct statvfs v {};
    if (::statvfs(dir_.c_str(), &v) != 0) return;
    const int64_t free = static_cast<int64_t>(v.f_bavail) * static_cast<int64_t>(v.f_frsize);
    if (free <= keep_free) return;
    std::FILE* f = std::fopen((dir_ + "/filler").c_str(), "wb");
    if (f == nullptr) return;
    std::string block(4096, 'x');
    for (int64_t n = 0; n + 4096 <= free - keep_free; n += 4096) std::fwrite(block.data(), 1, block.size(), f);
    std::fclose(f);
  }

 private:
  std::string dir_;
  int64_t bytes_;
  bool tmpfs_ = false;
};

}  // namespace nimble::test
