#pragma once
/// The rig's CAN frame layout: identifiers, signals, scaling, units and ranges.
///
/// This header and can_bridge/nimble_rig.dbc describe the same layout; the unit test
/// tests/can_bridge/test_can_dbc.cc parses the DBC file and compares it with every constant here,
/// so the two cannot drift apart.
///
/// Conventions (README.md has the table):
///  - Classical CAN, 11-bit standard identifiers, every frame exactly 8 data bytes (DLC 8).
///  - Byte order little-endian (Intel; DBC `@1`). A signal's start bit is the bit number of its
///    least significant bit, counting bit 0 of byte 0 as 0 and bit 7 of byte 7 as 63.
///  - physical = raw * factor + offset. Values outside [min, max] are clamped by the encoders
///    (and counted); a received raw value outside [min, max] makes the frame invalid.
///  - Every frame ends with a 4-bit rolling counter (byte 6, bits 4..7) and a CRC-8 (byte 7),
///    see crc8.h. All frames of one message carry the same counter value.
///  - Reserved bits are sent as 0 and ignored on reception.
///
/// One actuator_command_t travels as kCmdFlap + kCmdServo; one actuator_feedback_t as
/// kFbMotor + kFbServo + kFbStatus.

#include <array>
#include <cstddef>
#include <cstdint>

namespace nimble::can {

/// One CAN frame of the layout (a DBC `BO_`).
struct FrameSpec {
  const char* name;         ///< DBC message name
  uint32_t id;              ///< 11-bit standard identifier
  uint8_t length_bytes;     ///< required data length (DLC) [bytes]
  const char* transmitter;  ///< DBC node that sends the frame
};

/// One signal inside a frame (a DBC `SG_`), little-endian, physical = raw * factor + offset.
struct SignalSpec {
  const char* name;     ///< DBC signal name
  uint32_t frame_id;    ///< identifier of the frame that carries it
  uint8_t start_bit;    ///< bit number of the least significant bit (DBC little-endian start bit)
  uint8_t length_bits;  ///< width [bits]
  bool is_signed;       ///< two's complement raw value
  double factor;        ///< physical units per raw bit
  double offset;        ///< physical value of raw 0
  double min;           ///< smallest valid physical value
  double max;           ///< largest valid physical value
  const char* unit;     ///< DBC unit string
};

// --- frames ----------------------------------------------------------------------------------------
/// Flapping command: left/right flapping frequency, throttle, mode. Flight board -> actuators.
inline constexpr FrameSpec kCmdFlap{"NIMBLE_CMD_FLAP", 0x101, 8, "FLIGHT_BOARD"};
/// Servo command: dihedral and wing-root deflection, command sequence number.
inline constexpr FrameSpec kCmdServo{"NIMBLE_CMD_SERVO", 0x102, 8, "FLIGHT_BOARD"};
/// Motor feedback: measured flapping frequencies and applied throttle. Actuators -> flight board.
inline constexpr FrameSpec kFbMotor{"NIMBLE_FB_MOTOR", 0x181, 8, "ACTUATORS"};
/// Servo feedback: measured dihedral and wing-root deflection.
inline constexpr FrameSpec kFbServo{"NIMBLE_FB_SERVO", 0x182, 8, "ACTUATORS"};
/// Status feedback: command being executed, its age, safe state.
inline constexpr FrameSpec kFbStatus{"NIMBLE_FB_STATUS", 0x183, 8, "ACTUATORS"};

/// Frames of one actuator_command_t, in sending order.
inline constexpr std::array kCommandFrames{kCmdFlap, kCmdServo};
/// Frames of one actuator_feedback_t, in sending order.
inline constexpr std::array kFeedbackFrames{kFbMotor, kFbServo, kFbStatus};
/// Every frame of the layout.
inline constexpr std::array kAllFrames{kCmdFlap, kCmdServo, kFbMotor, kFbServo, kFbStatus};

// --- signals ---------------------------------------------------------------------------------------
// Flapping frequency: 0.01 rad/s per bit, 0..400 rad/s (the Nimble flaps near 107 rad/s).
inline constexpr SignalSpec kCmdFlapFreqLeft{"CmdFlapFreqLeft", 0x101, 0, 16, false, 0.01, 0.0, 0.0, 400.0, "rad/s"};
inline constexpr SignalSpec kCmdFlapFreqRight{"CmdFlapFreqRight", 0x101, 16, 16, false, 0.01, 0.0, 0.0, 400.0, "rad/s"};
inline constexpr SignalSpec kCmdThrottle{"CmdThrottle", 0x101, 32, 16, false, 0.01, 0.0, 0.0, 100.0, "%"};
/// actuator_command_t::mode: 0 MODE_LEFT_RIGHT, 1 MODE_DELTA_F (which pair the sender set).
inline constexpr SignalSpec kCmdMode{"CmdMode", 0x101, 48, 2, false, 1.0, 0.0, 0.0, 1.0, ""};
inline constexpr SignalSpec kCmdFlapCounter{"CmdFlapCounter", 0x101, 52, 4, false, 1.0, 0.0, 0.0, 15.0, ""};
inline constexpr SignalSpec kCmdFlapCrc{"CmdFlapCrc", 0x101, 56, 8, false, 1.0, 0.0, 0.0, 255.0, ""};

// Servo deflection from neutral: 0.0001 rad per bit, -1..1 rad.
inline constexpr SignalSpec kCmdDihedral{"CmdDihedral", 0x102, 0, 16, true, 0.0001, 0.0, -1.0, 1.0, "rad"};
inline constexpr SignalSpec kCmdWingRoot{"CmdWingRoot", 0x102, 16, 16, true, 0.0001, 0.0, -1.0, 1.0, "rad"};
/// Low 16 bits of actuator_command_t::seq.
inline constexpr SignalSpec kCmdSeq{"CmdSeq", 0x102, 32, 16, false, 1.0, 0.0, 0.0, 65535.0, ""};
inline constexpr SignalSpec kCmdServoCounter{"CmdServoCounter", 0x102, 52, 4, false, 1.0, 0.0, 0.0, 15.0, ""};
inline constexpr SignalSpec kCmdServoCrc{"CmdServoCrc", 0x102, 56, 8, false, 1.0, 0.0, 0.0, 255.0, ""};

inline constexpr SignalSpec kFbFlapFreqLeft{"FbFlapFreqLeft", 0x181, 0, 16, false, 0.01, 0.0, 0.0, 400.0, "rad/s"};
inline constexpr SignalSpec kFbFlapFreqRight{"FbFlapFreqRight", 0x181, 16, 16, false, 0.01, 0.0, 0.0, 400.0, "rad/s"};
/// actuator_feedback_t::throttle_pct: throttle deviation from hover trim (delta_t), so signed.
inline constexpr SignalSpec kFbThrottle{"FbThrottle", 0x181, 32, 16, true, 0.01, 0.0, -100.0, 100.0, "%"};
inline constexpr SignalSpec kFbMotorCounter{"FbMotorCounter", 0x181, 52, 4, false, 1.0, 0.0, 0.0, 15.0, ""};
inline constexpr SignalSpec kFbMotorCrc{"FbMotorCrc", 0x181, 56, 8, false, 1.0, 0.0, 0.0, 255.0, ""};

inline constexpr SignalSpec kFbDihedral{"FbDihedral", 0x182, 0, 16, true, 0.0001, 0.0, -1.0, 1.0, "rad"};
inline constexpr SignalSpec kFbWingRoot{"FbWingRoot", 0x182, 16, 16, true, 0.0001, 0.0, -1.0, 1.0, "rad"};
inline constexpr SignalSpec kFbServoCounter{"FbServoCounter", 0x182, 52, 4, false, 1.0, 0.0, 0.0, 15.0, ""};
inline constexpr SignalSpec kFbServoCrc{"FbServoCrc", 0x182, 56, 8, false, 1.0, 0.0, 0.0, 255.0, ""};

/// Low 16 bits of actuator_feedback_t::cmd_seq (0 when no command has been received).
inline constexpr SignalSpec kFbCmdSeq{"FbCmdSeq", 0x183, 0, 16, false, 1.0, 0.0, 0.0, 65535.0, ""};
/// actuator_feedback_t::cmd_age_us, 1 us per bit; raw kCmdAgeNoCommandRaw means "no command".
inline constexpr SignalSpec kFbCmdAge{"FbCmdAge", 0x183, 16, 24, false, 1.0, 0.0, 0.0, 16777215.0, "us"};
/// actuator_feedback_t::safe_state: 1 while the command-timeout hold is active.
inline constexpr SignalSpec kFbSafeState{"FbSafeState", 0x183, 40, 1, false, 1.0, 0.0, 0.0, 1.0, ""};
inline constexpr SignalSpec kFbStatusCounter{"FbStatusCounter", 0x183, 52, 4, false, 1.0, 0.0, 0.0, 15.0, ""};
inline constexpr SignalSpec kFbStatusCrc{"FbStatusCrc", 0x183, 56, 8, false, 1.0, 0.0, 0.0, 255.0, ""};

/// Raw FbCmdAge value that stands for "no command received" (cmd_age_us = cmd_seq = -1).
inline constexpr uint32_t kCmdAgeNoCommandRaw = 0xFFFFFF;
/// Largest command age that can be sent [us]; older commands are sent as this (counted).
inline constexpr int64_t kCmdAgeMax_us = 0xFFFFFE;

/// Every signal of the layout.
inline constexpr std::array kAllSignals{
    kCmdFlapFreqLeft, kCmdFlapFreqRight, kCmdThrottle,     kCmdMode,         kCmdFlapCounter,
    kCmdFlapCrc,      kCmdDihedral,      kCmdWingRoot,     kCmdSeq,          kCmdServoCounter,
    kCmdServoCrc,     kFbFlapFreqLeft,   kFbFlapFreqRight, kFbThrottle,      kFbMotorCounter,
    kFbMotorCrc,      kFbDihedral,       kFbWingRoot,      kFbServoCounter,  kFbServoCrc,
    kFbCmdSeq,        kFbCmdAge,         kFbSafeState,     kFbStatusCounter, kFbStatusCrc};

// --- rolling counter and checksum ------------------------------------------------------------------
/// Byte of the rolling counter (bits 4..7) in every frame.
inline constexpr std::size_t kCounterByte = 6;
/// Byte of the CRC-8 in every frame; the CRC covers the identifier and bytes 0..kCrcByte-1.
inline constexpr std::size_t kCrcByte = 7;
/// The rolling counter counts 0..15 and wraps.
inline constexpr unsigned kCounterModulo = 16;
/// A received counter is new if it is 1..kCounterMaxAdvance ahead of the last accepted one
/// (modulo 16); 0 (repeated) or more (older) is stale. Advances above 1 mean lost frames.
inline constexpr unsigned kCounterMaxAdvance = 7;

/// The frame spec with identifier `id`, or nullptr if `id` is not part of the layout.
constexpr const FrameSpec* find_frame(uint32_t id) {
  for (const FrameSpec& f : kAllFrames) {
    if (f.id == id) return &f;
  }
  return nullptr;
}

}  // namespace nimble::can
