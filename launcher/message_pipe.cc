#include "launcher/message_pipe.h"

#include <cstring>

namespace nimble::launcher {

MessagePipe::MessagePipe(Sink sink, std::size_t batch_bytes, std::size_t max_batches)
    : sink_(std::move(sink)),
      batch_bytes_(batch_bytes),
      max_batches_(max_batches),
      current_(std::make_unique<Batch>()) {
  current_->bytes.reserve(batch_bytes_);
  thread_ = std::thread([this] { receive_loop(); });
}

MessagePipe::~MessagePipe() {
  try {
    close();
  } catch (...) {
    // Reported by close() when called explicitly; a destructor must not throw.
  }
}

void MessagePipe::send(const std::string* channel, const void* data, int size, int64_t recv_ns, bool own_encoding) {
  Batch& b = *current_;
  const std::size_t offset = b.bytes.size();
  b.bytes.resize(offset + static_cast<std::size_t>(size));
  if (size > 0) std::memcpy(b.bytes.data() + offset, data, static_cast<std::size_t>(size));
  b.headers.push_back(Header{channel, recv_ns, offset, size, own_encoding});
  if (b.bytes.size() >= batch_bytes_) hand_over();
}

void MessagePipe::hand_over() {
  if (current_->headers.empty()) return;
  std::unique_lock<std::mutex> lock(mutex_);
  has_room_.wait(lock, [this] { return in_flight_ < max_batches_ || error_; });
  ++in_flight_;
  full_.push_back(std::move(current_));
  if (!free_.empty()) {
    current_ = std::move(free_.front());
    free_.pop_front();
  } else {
    current_ = std::make_unique<Batch>();
    current_->bytes.reserve(batch_bytes_);
  }
  lock.unlock();
  has_full_.notify_one();
}

void MessagePipe::receive_loop() {
  for (;;) {
    std::unique_ptr<Batch> batch;
    {
      std::unique_lock<std::mutex> lock(mutex_);
      has_full_.wait(lock, [this] { return !full_.empty() || closing_; });
      if (full_.empty()) return;  // closing, and everything delivered
      batch = std::move(full_.front());
      full_.pop_front();
    }
    try {
      if (!error_) {
        for (const Header& h : batch->headers)
          sink_(*h.channel, batch->bytes.data() + h.offset, h.size, h.recv_ns, h.own_encoding);
      }
    } catch (...) {
      std::lock_guard<std::mutex> lock(mutex_);
      error_ = std::current_exception();
    }
    batch->headers.clear();
    batch->bytes.clear();
    {
      std::lock_guard<std::mutex> lock(mutex_);
      free_.push_back(std::move(batch));
      --in_flight_;
    }
    has_room_.notify_one();
  }
}

void MessagePipe::close() {
  if (closed_) return;
  closed_ = true;
  hand_over();
  {
    std::lock_guard<std::mutex> lock(mutex_);
    closing_ = true;
  }
  has_full_.notify_one();
  thread_.join();
  if (error_) std::rethrow_exception(error_);
}

}  // namespace nimble::launcher
