#pragma once
/// nimble_can_bridge: one side of the CAN actuator link, as a rig process.
///
/// The side is the process name: `can_flight` or `can_rig` (bridge_config.h).
///
/// can_flight (the flight board's CAN interface):
///   Subscribes  ACTUATOR_CMD      actuator_command_t   512 Hz   -> NIMBLE_CMD_FLAP + NIMBLE_CMD_SERVO
///   Publishes   ACTUATOR_FB_CAN   actuator_feedback_t  100 Hz   <- NIMBLE_FB_MOTOR/SERVO/STATUS
/// can_rig (the HIL bench's actuator side):
///   Publishes   ACTUATOR_CMD_CAN  actuator_command_t   512 Hz   <- command frames; the plant's input
///   Subscribes  ACTUATOR_FB       actuator_feedback_t  100 Hz   -> feedback frames
/// Both:
///   Publishes   CAN_HEALTH        can_health_t         health_rate_hz (wall clock) and at exit
///               FAULT             error frames (CODE_CAN_ERROR_FRAME), dropped frames
///                                 (CODE_MESSAGE_MALFORMED), failed sends (CODE_QUEUE_DROP)
///   and HEARTBEAT, TIMING_HEALTH, STEP_ACK (ProcessNode).
///
/// Frames: can_bridge/nimble_rig.dbc. The socket receives the rig's identifier block
/// 0x100..0x1FF (one kernel filter) and error frames. With `can_bridge.fd: true` the same 8-byte frames travel as
/// CAN FD frames (CANFD_BRS set); either side then accepts classical and FD frames of 8 bytes (an
/// FD frame of another length is a wrong length). Every received frame goes through the decoder, which
/// counts and drops unknown identifiers, wrong lengths, bad checksums, stale counters and
/// out-of-range values; nothing a frame contains can stop the bridge.
///
/// Lockstep: each side is a participant due at the controller's rate. At each control cycle
/// it acknowledges only once that cycle's command has crossed its part of the link
/// (can_flight: sent as frames; can_rig: decoded and published), so the plant steps on the
/// command exactly as it would over LCM and the truth is the same over either link.
///
/// Decoded commands carry `utime` = the control cycle's rig time, `source` = the process
/// name and `input_utime` = -1 (the frames do not carry it).

#include <cstdint>
#include <memory>
#include <optional>
#include <string>

#include <nimble/actuator_command_t.hpp>
#include <nimble/actuator_feedback_t.hpp>

#include <array>

#include "can_bridge/bridge_config.h"
#include "can_bridge/can_socket.h"
#include "can_bridge/can_faults.h"
#include "can_bridge/candump_log.h"
#include "can_bridge/codec.h"
#include "can_bridge/inprocess_can_bus.h"
#include "scenario/scenario.h"
#include "transport/node.h"

namespace nimble::can {

class CanBridgeNode {
 public:
  enum class Role { kFlight, kRig };

  /// @throws ConfigError on bad configuration or an unknown process name; CanError if the
  ///         interface cannot be opened (the message names it and says how to create it).
  ///         With `inprocess_bus` (an in-process run, options.hub set) the side sends and
  ///         receives its frames there instead of on the interface.
  CanBridgeNode(const Scenario& scenario, const transport::NodeOptions& options,
                InprocessCanBus* inprocess_bus = nullptr);
  ~CanBridgeNode();

  int run();
  transport::ProcessNode& node() { return *node_; }
  Role role() const { return role_; }

  /// Reads the frames waiting on the socket (also called by the node's wait loop); returns
  /// how many it read.
  int drain_socket();
  /// Publishes CAN_HEALTH now.
  void publish_health();

 private:
  void on_command(const actuator_command_t& cmd);
  void on_feedback(const actuator_feedback_t& fb);
  void on_frame(const ReceivedFrame& rx);
  void on_error_frame(const ReceivedFrame& rx);
  void reject(const ReceivedFrame& rx, DecodeResult result);
  void send(const can_frame& frame);
  /// Sends the frames of message `message` in `direction` (time `utime`) through the link's
  /// faults (CanLinkFaults): lost and bus-off frames are not sent, corrupted ones have a bit flipped.
  template <std::size_t N>
  void send_message(const std::array<can_frame, N>& frames, CanLinkFaults::Direction direction, int64_t message,
                    int64_t utime);
  /// Enters or leaves an injected bus-off at `utime` (FAULT CAN_ERROR_FRAME, CAN_HEALTH state).
  void update_bus_off(int64_t utime);
  void log_frame(const ReceivedFrame& rx);
  /// The candump log could not be written: a FATAL fault naming why, and the run ends.
  void candump_failed();
  void on_cycle(int64_t sim_time_ns);
  /// A command crossed this side's part of the link; releases a held STEP_ACK once every
  /// due control cycle has its command.
  void on_command_crossed();
  int64_t rig_time_us() const;

  Role role_;
  CanBridgeConfig config_;
  std::unique_ptr<transport::ProcessNode> node_;
  std::unique_ptr<FramePort> socket_;  // the interface, or an in-process bus endpoint
  bool candump_failure_reported_ = false;
  std::unique_ptr<CandumpWriter> candump_;
  int64_t cycle_period_ns_ = 0;

  CommandEncoder command_encoder_;
  FeedbackEncoder feedback_encoder_;
  CommandDecoder command_decoder_;
  FeedbackDecoder feedback_decoder_;

  // Lockstep: control cycles acknowledged, and commands that crossed the link.
  int64_t cycles_due_ = 0;
  int64_t commands_crossed_ = 0;

  int64_t messages_to_can_ = 0, messages_to_lcm_ = 0;
  /// Faults of the link (scenario faults with target CAN), and the messages numbered for them.
  std::unique_ptr<CanLinkFaults> link_faults_;
  int64_t command_messages_ = 0, feedback_messages_ = 0;
  int64_t frames_withheld_ = 0;      ///< frames a link fault lost or a bus-off kept back
  int64_t commands_never_came_ = 0;  ///< rig side, lockstep: cycles acknowledged without their command
  /// Rig side, lockstep, with link faults: whether command message `m` (m = shadow_next_; asked in order, once each)
  /// will be decoded whole: the flight side's frame fates, then the decoder's counter rule on a
  /// shadow assembler (a long gap makes the next few counters look stale, and they are dropped).
  /// The controller numbers its commands' rolling counters m mod 16.
  bool command_will_arrive(int64_t m);
  /// Rig side, lockstep, with link faults: counts as crossed the owed commands that will never arrive.
  void skip_lost_commands();
  bool shadow_arrives_ = true;  ///< command_will_arrive() of the command shadow_next_ - 1
  FrameAssembler shadow_assembler_{kCommandFrames.size()};
  DecodeStats shadow_stats_;
  int64_t shadow_next_ = 0;
  const contract::FaultSpec* active_link_fault_ = nullptr;  ///< the link fault active at the last message
  bool injected_bus_off_ = false;
  int64_t feedback_seq_ = 0;
  int8_t bus_state_ = 0;
  std::string last_error_;
  int64_t health_seq_ = 0;
  int64_t next_health_wall_ns_ = 0;
  int64_t health_period_ns_ = 0;
};

}  // namespace nimble::can
