#pragma once
/// The scenario's actuator link: `actuator_link: lcm | can` and the `can_bridge` section.
///
///   actuator_link: can            # lcm (default): the plant takes ACTUATOR_CMD directly
///   can_bridge:
///     interface: vcan0            # SocketCAN interface, e.g. vcan0 (virtual) or can0
///     create_virtual: true        # rig run creates it as a vcan in the run's network namespace
///     candump_log: true           # the rig side writes <log>.candump (canplayer replays it)
///     health_rate_hz: 2           # CAN_HEALTH rate of each side [Hz]
///     receive_buffer_bytes: 0     # SO_RCVBUF of the bridge sockets; 0 = kernel default
///     fd: false                   # true: CAN FD frames (same 8-byte layout, bit rate switch);
///                                 #   the interface needs MTU 72 (a vcan rig run creates gets it)
///
/// With `actuator_link: can` the launcher adds the two sides of the bridge to the run's
/// processes: `can_flight` (flight board: ACTUATOR_CMD -> frames, feedback frames ->
/// ACTUATOR_FB_CAN) and `can_rig` (HIL bench: command frames -> ACTUATOR_CMD_CAN for the plant,
/// ACTUATOR_FB -> frames). Both run the executable nimble_can_bridge.

#include <string>

#include "contract/default_rates.h"
#include "core/config.h"
#include "core/param_table.h"

namespace nimble::can {

/// Process names of the two sides of the bridge.
inline const std::string kFlightProcess = "can_flight";
inline const std::string kRigProcess = "can_rig";

struct CanBridgeConfig {
  std::string interface = "vcan0";
  bool create_virtual = true;
  bool candump_log = true;
  /// Set by the launcher in the resolved scenario (next to the run's log); empty: no log.
  std::string candump_file;
  double health_rate_hz = contract::kDefaultCanHealthRateHz;
  int receive_buffer_bytes = 0;
  /// CAN FD: both sides send every frame as an FD frame of 8 bytes with CANFD_BRS and accept
  /// classical and FD frames of 8 bytes. The interface needs the CAN FD MTU (72).
  bool fd = false;
};

/// The section's numeric and boolean parameters (defaults: CanBridgeConfig's); interface and
/// candump_file are read on their own. The loader and `rig params` use the table.
const ParamTable<CanBridgeConfig>& can_bridge_params();

/// Reads and validates the `can_bridge` section (every key optional).
/// @throws ConfigError naming the key, e.g. an interface name longer than 15 characters.
CanBridgeConfig can_bridge_config_from(ConfigMap& section);

}  // namespace nimble::can
