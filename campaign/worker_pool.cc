#include "campaign/worker_pool.h"

#include <poll.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <stdexcept>

namespace nimble::campaign {
namespace {

constexpr std::size_t kNone = static_cast<std::size_t>(-1);

struct Worker {
  pid_t pid = -1;
  int to_fd = -1;    ///< item indices to the worker
  int from_fd = -1;  ///< result lines from it
  std::size_t item = kNone;
  std::string buffer;
};

[[noreturn]] void fail(const std::string& what) {
  throw std::runtime_error("worker pool: " + what + ": " + std::strerror(errno));
}

bool write_all(int fd, const void* data, std::size_t size) {
  const auto* p = static_cast<const char*>(data);
  while (size > 0) {
    const ssize_t k = ::write(fd, p, size);
    if (k < 0 && errno == EINTR) continue;
    if (k <= 0) return false;
    p += k;
    size -= static_cast<std::size_t>(k);
  }
  return true;
}

/// The worker's loop: an index in, a line out, until the parent closes the pipe.
[[noreturn]] void worker_main(int in_fd, int out_fd, const std::function<std::string(std::size_t)>& work) {
  for (;;) {
    std::uint64_t index = 0;
    std::size_t got = 0;
    while (got < sizeof index) {
      const ssize_t k = ::read(in_fd, reinterpret_cast<char*>(&index) + got, sizeof index - got);
      if (k < 0 && errno == EINTR) continue;
      if (k <= 0) ::_exit(0);
      got += static_cast<std::size_t>(k);
    }
    std::string line;
    try {
      line = work(static_cast<std::size_t>(index));
    } catch (const std::exception& e) {
      line = std::string("error ") + e.what();
    }
    for (char& c : line) {
      if (c == '\n') c = ' ';
    }
    line += '\n';
    if (!write_all(out_fd, line.data(), line.size())) ::_exit(1);
  }
}

Worker spawn(std::vector<Worker>& all, const std::function<std::string(std::size_t)>& work) {
  int to[2], from[2];
  if (::pipe(to) != 0) fail("pipe");
  if (::pipe(from) != 0) fail("pipe");
  std::fflush(stdout);
  std::fflush(stderr);
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) fail("fork");
  if (pid == 0) {
    // A worker does not outlive the pool that feeds it.
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(1);
    for (const Worker& w : all) {
      if (w.to_fd >= 0) ::close(w.to_fd);
      if (w.from_fd >= 0) ::close(w.from_fd);
    }
    ::close(to[1]);
    ::close(from[0]);
    worker_main(to[0], from[1], work);
  }
  ::close(to[0]);
  ::close(from[1]);
  Worker w;
  w.pid = pid;
  w.to_fd = to[1];
  w.from_fd = from[0];
  return w;
}

std::string how_it_ended(pid_t pid) {
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0 && errno == EINTR) {
  }
  return exit_description(status);
}

void retire(Worker& w) {
  if (w.to_fd >= 0) ::close(w.to_fd);
  if (w.from_fd >= 0) ::close(w.from_fd);
  w.to_fd = w.from_fd = -1;
}

}  // namespace

std::string exit_description(int status) {
  if (WIFSIGNALED(status)) return "killed by signal " + std::to_string(WTERMSIG(status));
  return "exit code " + std::to_string(WEXITSTATUS(status));
}

std::vector<std::string> run_in_workers(std::size_t n, int jobs, const PoolWork& pool) {
  const auto& work = pool.work;
  std::vector<std::string> results(n);
  if (n == 0) return results;
  struct sigaction ignore {
  }, old_pipe{};
  ignore.sa_handler = SIG_IGN;
  sigaction(SIGPIPE, &ignore, &old_pipe);  // a worker that died must not take the parent with it

  std::vector<Worker> workers;
  std::size_t next = 0, done = 0;
  const auto dispatch = [&](Worker& w) {
    if (next >= n) {
      ::close(w.to_fd);  // the worker ends when its pipe closes
      w.to_fd = -1;
      return;
    }
    const std::uint64_t index = next;
    w.item = next++;
    if (pool.started) pool.started(w.item);
    write_all(w.to_fd, &index, sizeof index);  // a worker that died is seen as end of file below
  };
  const std::size_t count = std::min<std::size_t>(n, static_cast<std::size_t>(std::max(1, jobs)));
  for (std::size_t k = 0; k < count; ++k) workers.push_back(spawn(workers, work));
  for (Worker& w : workers) dispatch(w);

  while (done < n) {
    std::vector<pollfd> fds;
    std::vector<std::size_t> owner;
    for (std::size_t k = 0; k < workers.size(); ++k) {
      if (workers[k].from_fd >= 0 && workers[k].item != kNone) {
        fds.push_back({workers[k].from_fd, POLLIN, 0});
        owner.push_back(k);
      }
    }
    if (fds.empty()) throw std::runtime_error("worker pool: no worker left with items outstanding");
    if (::poll(fds.data(), fds.size(), -1) < 0) {
      if (errno == EINTR) continue;
      fail("poll");
    }
    for (std::size_t f = 0; f < fds.size(); ++f) {
      if (fds[f].revents == 0) continue;
      Worker& w = workers[owner[f]];
      char chunk[4096];
      const ssize_t k = ::read(w.from_fd, chunk, sizeof chunk);
      if (k < 0 && errno == EINTR) continue;
      if (k > 0) {
        w.buffer.append(chunk, static_cast<std::size_t>(k));
        const std::size_t eol = w.buffer.find('\n');
        if (eol == std::string::npos) continue;
        const std::size_t item = w.item;
        results[item] = w.buffer.substr(0, eol);
        w.buffer.erase(0, eol + 1);
        w.item = kNone;
        ++done;
        if (pool.finished) pool.finished(item, results[item], done);
        if (pool.forget) std::string().swap(results[item]);
        dispatch(w);
        continue;
      }
      // End of file with an item outstanding: the worker died on it.
      const std::size_t item = w.item;
      retire(w);
      w.item = kNone;
      results[item] = pool.died(item, how_it_ended(w.pid));
      w.pid = -1;
      ++done;
      if (pool.finished) pool.finished(item, results[item], done);
      if (pool.forget) std::string().swap(results[item]);
      if (next < n) {
        workers.push_back(spawn(workers, work));
        dispatch(workers.back());
      }
    }
  }
  for (Worker& w : workers) {
    retire(w);
    if (w.pid > 0) how_it_ended(w.pid);
  }
  sigaction(SIGPIPE, &old_pipe, nullptr);
  return results;
}

}  // namespace nimble::campaign
