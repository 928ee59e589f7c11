#pragma once
/// SocketCAN raw socket (PF_CAN / CAN_RAW) for the rig's frames, classical CAN and optionally
/// CAN FD (CAN_RAW_FD_FRAMES).
///
/// Opening throws (with the interface name, the errno and a hint); after that nothing throws:
/// sending retries a full queue (ENOBUFS / EAGAIN) with a bounded back-off and then drops the
/// frame, and every outcome is counted in CanSocketStats.

#include <linux/can.h>

#include <chrono>
#include <cstdint>
#include <functional>
#include <stdexcept>
#include <string>
#include <vector>

#include "can_bridge/error_frame.h"

namespace nimble::can {

/// Failure to open or configure a CAN socket.
class CanError : public std::runtime_error {
 public:
  CanError(const std::string& interface, int errno_value, const std::string& message);
  /// Interface the socket was opened on, e.g. "vcan0".
  const std::string& interface() const { return interface_; }
  /// errno of the failed call (0 if none).
  int errno_value() const { return errno_value_; }

 private:
  std::string interface_;
  int errno_value_;
};

/// Back-off for a full transmit queue: retry after first_backoff, doubling up to max_backoff,
/// at most max_retries times; then the frame is dropped.
struct SendRetryPolicy {
  int max_retries = 8;                          ///< retries after the first attempt
  std::chrono::microseconds first_backoff{20};  ///< wait before the first retry
  std::chrono::microseconds max_backoff{2000};  ///< longest single wait
};

/// Everything a CanSocket counts.
struct CanSocketStats {
  uint64_t frames_sent = 0;         ///< frames the kernel accepted (classical and FD)
  uint64_t frames_received = 0;     ///< data frames received (classical and FD)
  uint64_t fd_frames_sent = 0;      ///< of frames_sent: CAN FD frames
  uint64_t fd_frames_received = 0;  ///< of frames_received: CAN FD frames
  uint64_t error_frames = 0;        ///< error frames received (CAN_RAW_ERR_FILTER)
  uint64_t send_enobufs = 0;        ///< send attempts that returned ENOBUFS (queue full)
  uint64_t send_eagain = 0;         ///< send attempts that returned EAGAIN (socket buffer full)
  uint64_t send_retries = 0;        ///< retries after ENOBUFS / EAGAIN
  uint64_t send_dropped = 0;        ///< frames given up after max_retries
  uint64_t send_errors = 0;         ///< sends failed with another errno (e.g. ENETDOWN)
  uint64_t receive_errors = 0;      ///< failed receive calls
  uint64_t receive_dropped = 0;     ///< frames the kernel dropped for this socket because its
                                    ///< receive queue was full (SO_RXQ_OVFL; known with the
                                    ///< next frame received after the drops)
  uint64_t missing_timestamps = 0;  ///< received frames without a kernel timestamp
  int last_errno = 0;               ///< errno of the last failed call
};

/// Exact-match filters for the rig's identifiers (frame_layout.h).
std::vector<can_filter> rig_filters();

/// One filter for the rig's whole identifier block: every standard data frame with an
/// identifier 0x100..0x1FF (no extended or remote frames). Frames of other nodes on a shared
/// bus stay in the kernel; unexpected identifiers within the rig's block reach the decoders,
/// which count them.
can_filter rig_block_filter();

/// Options of CanSocket::open. The defaults receive the rig's five identifiers and all error
/// frames, with kernel receive timestamps.
struct CanSocketOptions {
  /// Receive filters (CAN_RAW_FILTER). Empty: receive no data frames (a send-only socket).
  std::vector<can_filter> filters = rig_filters();
  bool receive_all = false;                  ///< receive every data frame (filters ignored)
  bool error_frames = true;                  ///< CAN_RAW_ERR_FILTER with error_mask
  can_err_mask_t error_mask = CAN_ERR_MASK;  ///< error classes to receive
  bool timestamps = true;                    ///< SO_TIMESTAMPING (software, and hardware where the driver has it)
  bool receive_own = false;                  ///< CAN_RAW_RECV_OWN_MSGS
  int send_buffer_bytes = 0;                 ///< SO_SNDBUF; 0: kernel default
  int receive_buffer_bytes = 0;              ///< SO_RCVBUF; 0: kernel default
  /// CAN FD (CAN_RAW_FD_FRAMES): send(const canfd_frame&) works and receive() returns FD frames
  /// too. The interface must have the CAN FD MTU (CANFD_MTU, 72); open() throws otherwise.
  bool fd = false;
  SendRetryPolicy retry;  ///< back-off on a full queue
};

/// Result of CanSocket::send.
enum class SendResult : uint8_t {
  kSent,     ///< the kernel accepted the frame
  kDropped,  ///< the queue stayed full through every retry; frame dropped
  kError,    ///< another error (stats.last_errno)
};

/// Result of CanSocket::receive.
enum class ReceiveResult : uint8_t {
  kFrame,    ///< a data frame or an error frame was received
  kTimeout,  ///< nothing within the timeout
  kError,    ///< receive failed (stats.last_errno)
};

/// A received frame with its kernel timestamps.
///
/// Classical frames are in `frame`. CAN FD frames (sockets opened with CanSocketOptions::fd) are
/// in `fd_frame`; those of at most 8 bytes are also copied into `frame` (identifier, length and
/// data), so code that takes a can_frame handles them unchanged. For longer FD frames `frame`
/// holds only the identifier, with length 0.
struct ReceivedFrame {
  can_frame frame{};             ///< the frame as received (classical), or see above (FD)
  bool is_fd = false;            ///< a CAN FD frame (CANFD_MTU bytes from the kernel)
  canfd_frame fd_frame{};        ///< the FD frame (is_fd only), up to 64 data bytes
  uint8_t fd_flags = 0;          ///< its flags: CANFD_BRS, CANFD_ESI, CANFD_FDF (is_fd only)
  bool is_error_frame = false;   ///< CAN_ERR_FLAG set; see `error`
  ErrorFrameInfo error;          ///< decoded error frame (is_error_frame only)
  bool has_kernel_time = false;  ///< software receive timestamp present
  int64_t kernel_time_ns = 0;    ///< software receive timestamp, CLOCK_REALTIME [ns]
  int64_t hardware_time_ns = 0;  ///< hardware receive timestamp [ns]; 0 if none
};

/// One send attempt: returns 0 if the frame was accepted, else the errno value.
using SendAttempt = std::function<int()>;
/// Waits for the given time (injectable for tests).
using SleepFunction = std::function<void(std::chrono::microseconds)>;

/// The first 8 bytes of an FD frame as a classical frame: identifier, length (if at most
/// CAN_MAX_DLEN; else 0) and data. See ReceivedFrame.
can_frame classical_view(const canfd_frame& frame);

/// A classical frame as an FD frame with the same identifier, length and data, and `flags`
/// (e.g. CANFD_BRS).
canfd_frame to_fd_frame(const can_frame& frame, uint8_t flags);

/// Calls `attempt` until it succeeds, retrying ENOBUFS / EAGAIN / EWOULDBLOCK per `policy` with
/// `sleep` between tries; counts every outcome in `stats`. Never throws.
SendResult send_with_retry(const SendAttempt& attempt, const SendRetryPolicy& policy, CanSocketStats& stats,
                           const SleepFunction& sleep);

/// Where a side of the CAN bridge sends and receives its frames: a SocketCAN socket
/// (CanSocket) or, in a run flown in one process, an endpoint of an InprocessCanBus.
class FramePort {
 public:
  virtual ~FramePort() = default;
  /// Sends one classical frame; never throws.
  virtual SendResult send(const can_frame& frame) = 0;
  /// Sends one CAN FD frame; never throws.
  virtual SendResult send(const canfd_frame& frame) = 0;
  /// Waits up to `timeout_ms` (0: poll) for one frame.
  virtual ReceiveResult receive(ReceivedFrame* out, int timeout_ms) = 0;
  /// Counters since the port was opened.
  virtual const CanSocketStats& stats() const = 0;
  /// Descriptor that becomes readable when frames wait; -1 if there is none (in process).
  virtual int fd() const = 0;
};

/// A PF_CAN / CAN_RAW socket bound to one interface; non-blocking.
class CanSocket : public FramePort {
 public:
  /// Opens a raw CAN socket on `interface` (e.g. "vcan0", "can0") and applies `options`.
  /// @throws CanError naming the interface and errno; on EAFNOSUPPORT the message says that the
  ///         kernel has no CAN support and that tests get it through tools/canvm/canvm. With
  ///         options.fd on an interface whose MTU is not CANFD_MTU, the message gives the
  ///         `ip link set <if> mtu 72` fix.
  static CanSocket open(const std::string& interface, const CanSocketOptions& options = {});

  CanSocket(CanSocket&& other) noexcept;
  CanSocket& operator=(CanSocket&& other) noexcept;
  CanSocket(const CanSocket&) = delete;
  CanSocket& operator=(const CanSocket&) = delete;
  ~CanSocket() override;

  /// Sends one classical CAN frame without blocking; a full queue is retried with back-off.
  SendResult send(const can_frame& frame) override;
  /// Sends one CAN FD frame (socket opened with CanSocketOptions::fd), same retry policy.
  /// Without fd the kernel refuses it: kError with EINVAL.
  SendResult send(const canfd_frame& frame) override;

  /// Waits up to `timeout_ms` (0: poll, < 0: forever) for one frame, classical or (with fd) CAN
  /// FD. Error frames are returned too (is_error_frame) and counted separately.
  ReceiveResult receive(ReceivedFrame* out, int timeout_ms) override;

  /// Counters since the socket was opened.
  const CanSocketStats& stats() const override { return stats_; }
  /// Interface name the socket is bound to.
  const std::string& interface() const { return interface_; }
  /// The socket's file descriptor (for poll loops).
  int fd() const override { return fd_; }
  /// True if opened with CanSocketOptions::fd (CAN FD frames enabled).
  bool fd_enabled() const { return fd_enabled_; }

 private:
  CanSocket(int fd, std::string interface, SendRetryPolicy retry);

  int fd_ = -1;
  std::string interface_;
  SendRetryPolicy retry_;
  CanSocketStats stats_;
  bool timestamps_ = true;
  bool fd_enabled_ = false;
};

}  // namespace nimble::can
