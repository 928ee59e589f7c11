#pragma once
/// MessagePipe: hands messages from the thread that flies an in-process run to a second
/// thread that records and monitors them, so that the log and the summary cost the flight no
/// time on a machine with a second core. Messages travel in batches (one lock per batch);
/// their order is kept; a full pipe makes the sender wait, so nothing is ever dropped.

#include <condition_variable>
#include <cstdint>
#include <deque>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

namespace nimble::launcher {

class MessagePipe {
 public:
  /// Runs on the receiving thread for every message, in order. `channel` refers to a string
  /// that lives as long as the pipe is open; `own_encoding` is what send() was told.
  using Sink =
      std::function<void(const std::string& channel, const void* data, int size, int64_t recv_ns, bool own_encoding)>;

  /// Starts the receiving thread. `max_batches`: batches in flight before send() waits.
  explicit MessagePipe(Sink sink, std::size_t batch_bytes = 1 << 17, std::size_t max_batches = 16);
  /// Closes the pipe (see close()).
  ~MessagePipe();
  MessagePipe(const MessagePipe&) = delete;
  MessagePipe& operator=(const MessagePipe&) = delete;

  /// Sends one message (copied). `channel` must stay valid until close() returns.
  /// `own_encoding`: the bytes are the rig's own encoding of a message
  /// (transport::InprocessHub::delivering_own_encoding()), passed on to the sink.
  void send(const std::string* channel, const void* data, int size, int64_t recv_ns, bool own_encoding = false);
  /// Delivers everything sent and stops the receiving thread. An exception the sink threw is
  /// rethrown here. Idempotent.
  void close();

 private:
  struct Header {
    const std::string* channel;
    int64_t recv_ns;
    std::size_t offset;
    int size;
    bool own_encoding;
  };
  struct Batch {
    std::vector<Header> headers;
    std::vector<unsigned char> bytes;
  };
  void hand_over();  // current_ -> full_ (caller holds no lock)
  void receive_loop();

  Sink sink_;
  std::size_t batch_bytes_, max_batches_;
  std::unique_ptr<Batch> current_;
  std::mutex mutex_;
  std::condition_variable has_full_, has_room_;
  std::deque<std::unique_ptr<Batch>> full_, free_;
  std::size_t in_flight_ = 0;
  bool closing_ = false, closed_ = false;
  std::exception_ptr error_;
  std::thread thread_;
};

}  // namespace nimble::launcher
