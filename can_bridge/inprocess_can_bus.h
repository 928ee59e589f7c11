#pragma once
/// InprocessCanBus: the CAN link of a run flown in one process (`rig run --clock inprocess`).
///
/// Each side of the bridge attaches an endpoint (a FramePort) and sends real frames, encoded
/// by the rig's codec; every frame reaches every other endpoint, in order, as on a virtual
/// CAN bus without CAN_RAW_RECV_OWN_MSGS. Nothing is lost, nothing is late: the bus has no
/// timing and no error frames of its own. A classical frame arrives as a classical frame, an
/// FD frame as an FD frame with its first 8 bytes also in `frame` (what CanSocket does).

#include <cstddef>
#include <deque>
#include <memory>
#include <string>
#include <vector>

#include "can_bridge/can_socket.h"

namespace nimble::can {

class InprocessCanBus {
 public:
  /// A new endpoint on the bus, named like the interface it stands for. `fd`: it sends and
  /// receives CAN FD frames too (a classical endpoint refuses to send one, like the kernel).
  /// The bus must outlive the endpoint.
  std::unique_ptr<FramePort> attach(const std::string& interface_name, bool fd);

  /// Frames carried so far.
  std::size_t frames() const { return frames_; }

 private:
  class Endpoint;
  void deliver(const Endpoint* from, const ReceivedFrame& frame);

  std::vector<Endpoint*> endpoints_;
  std::size_t frames_ = 0;
  friend class Endpoint;
};

}  // namespace nimble::can
