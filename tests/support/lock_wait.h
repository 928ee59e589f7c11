#pragma once
/// Test support: who holds an output's flock (core/output_lock.h), and bounded waits for it to be
/// taken or let go. Header-only; the test links nimble_core.

#include <sys/stat.h>

#include <chrono>
#include <string>
#include <thread>

#include "core/output_lock.h"

namespace nimble::test {

/// The pid holding the flock on `path` (-1: none, or no such file).
inline int holder_of(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) != 0) return -1;
  const auto h = nimble::lock_holder(st.st_dev, st.st_ino);
  return h ? h->pid : -1;
}

/// Waits (bounded by `limit`) until someone holds the lock on `path`; returns its pid or -1.
inline int wait_for_holder(const std::string& path, std::chrono::milliseconds limit = std::chrono::seconds(20)) {
  const auto end = std::chrono::steady_clock::now() + limit;
  do {
    const int pid = holder_of(path);
    if (pid > 0) return pid;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  } while (std::chrono::steady_clock::now() < end);
  return -1;
}

/// Waits (bounded by `limit`) until nobody holds the lock on `path`; false if someone still does.
inline bool wait_for_no_holder(const std::string& path, std::chrono::milliseconds limit = std::chrono::seconds(5)) {
  const auto end = std::chrono::steady_clock::now() + limit;
  do {
    if (holder_of(path) == -1) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  } while (std::chrono::steady_clock::now() < end);
  return false;
}

}  // namespace nimble::test
