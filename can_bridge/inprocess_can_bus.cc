#include "can_bridge/inprocess_can_bus.h"

#include <cerrno>
#include <ctime>

namespace nimble::can {

namespace {

int64_t realtime_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

}  // namespace

class InprocessCanBus::Endpoint : public FramePort {
 public:
  Endpoint(InprocessCanBus& bus, std::string name, bool fd) : bus_(bus), name_(std::move(name)), fd_(fd) {}
  ~Endpoint() override {
    auto& list = bus_.endpoints_;
    for (auto it = list.begin(); it != list.end(); ++it) {
      if (*it == this) {
        list.erase(it);
        break;
      }
    }
  }

  SendResult send(const can_frame& frame) override {
    ReceivedFrame rx;
    rx.frame = frame;
    bus_.deliver(this, rx);
    ++stats_.frames_sent;
    return SendResult::kSent;
  }

  SendResult send(const canfd_frame& frame) override {
    if (!fd_) {
      // What the kernel does on a socket without CAN_RAW_FD_FRAMES.
      ++stats_.send_errors;
      stats_.last_errno = EINVAL;
      return SendResult::kError;
    }
    ReceivedFrame rx;
    rx.is_fd = true;
    rx.fd_frame = frame;
    rx.fd_flags = frame.flags;
    rx.frame = classical_view(frame);
    bus_.deliver(this, rx);
    ++stats_.frames_sent;
    ++stats_.fd_frames_sent;
    return SendResult::kSent;
  }

  ReceiveResult receive(ReceivedFrame* out, int /*timeout_ms*/) override {
    // Nothing arrives while this thread waits: the bus is the thread's own.
    if (queue_.empty()) return ReceiveResult::kTimeout;
    *out = queue_.front();
    queue_.pop_front();
    ++stats_.frames_received;
    if (out->is_fd) ++stats_.fd_frames_received;
    return ReceiveResult::kFrame;
  }

  const CanSocketStats& stats() const override { return stats_; }
  int fd() const override { return -1; }

  void accept(const ReceivedFrame& frame) {
    if (frame.is_fd && !fd_) return;  // a classical socket never sees FD frames
    queue_.push_back(frame);
    queue_.back().has_kernel_time = true;
    queue_.back().kernel_time_ns = realtime_ns();
  }

 private:
  InprocessCanBus& bus_;
  std::string name_;
  bool fd_;
  std::deque<ReceivedFrame> queue_;
  CanSocketStats stats_;
};

std::unique_ptr<FramePort> InprocessCanBus::attach(const std::string& interface_name, bool fd) {
  auto endpoint = std::make_unique<Endpoint>(*this, interface_name, fd);
  endpoints_.push_back(endpoint.get());
  return endpoint;
}

void InprocessCanBus::deliver(const Endpoint* from, const ReceivedFrame& frame) {
  ++frames_;
  for (Endpoint* e : endpoints_) {
    if (e != from) e->accept(frame);
  }
}

}  // namespace nimble::can
