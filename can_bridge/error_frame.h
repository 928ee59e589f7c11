#pragma once
/// Decoding of SocketCAN error frames (CAN_ERR_FLAG, linux/can/error.h) into readable form.

#include <linux/can.h>

#include <cstdint>
#include <string>

namespace nimble::can {

/// What an error frame reports. The flags summarise the controller state; `description` lists
/// every reported condition in words.
struct ErrorFrameInfo {
  uint32_t error_class = 0;           ///< CAN_ERR_* class bits of can_id (without CAN_ERR_FLAG)
  bool bus_off = false;               ///< controller went bus-off (CAN_ERR_BUSOFF)
  bool error_passive = false;         ///< RX or TX error-passive (CAN_ERR_CRTL_*_PASSIVE)
  bool error_warning = false;         ///< RX or TX error-warning level (CAN_ERR_CRTL_*_WARNING)
  bool back_to_error_active = false;  ///< recovered to error-active (CAN_ERR_CRTL_ACTIVE)
  bool restarted = false;             ///< controller restarted (CAN_ERR_RESTARTED)
  bool overflow = false;              ///< controller RX or TX buffer overflow (frames lost)
  bool has_error_counters = false;    ///< tx/rx_error_count are valid (CAN_ERR_CNT)
  uint8_t tx_error_count = 0;         ///< transmit error counter (TEC)
  uint8_t rx_error_count = 0;         ///< receive error counter (REC)
  std::string description;            ///< e.g. "bus-off; controller: TX error-passive; TEC 128 REC 0"
};

/// True if `frame` is an error frame.
inline bool is_error_frame(const can_frame& frame) { return (frame.can_id & CAN_ERR_FLAG) != 0; }

/// Decodes an error frame. For a frame without CAN_ERR_FLAG the result has error_class 0 and the
/// description "not an error frame". Never throws on any content.
ErrorFrameInfo decode_error_frame(const can_frame& frame);

}  // namespace nimble::can
