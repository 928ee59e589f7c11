#include "can_bridge/bridge_config.h"

#include <net/if.h>

namespace nimble::can {

const ParamTable<CanBridgeConfig>& can_bridge_params() {
  using C = CanBridgeConfig;
  static const ParamTable<C> table = {
      {"create_virtual", &C::create_virtual, Range::any(), "-",
       "rig run creates the interface as a vcan in the run's network namespace"},
      {"candump_log", &C::candump_log, Range::any(), "-",
       "can_rig writes every frame it receives to <log>.candump (candump -L format)"},
      {"health_rate_hz", &C::health_rate_hz, Range::closed(0.1, 50.0), "Hz",
       "CAN_HEALTH of each side, per wall second"},
      {"receive_buffer_bytes", &C::receive_buffer_bytes, Range::closed(0, 64 * 1024 * 1024), "bytes",
       "SO_RCVBUF of the sockets; 0: the kernel's default"},
      {"fd", &C::fd, Range::any(), "-",
       "every frame as an 8-byte CAN FD frame with CANFD_BRS; the interface needs MTU 72"},
  };
  return table;
}

CanBridgeConfig can_bridge_config_from(ConfigMap& m) {
  CanBridgeConfig c;
  c.interface = m.get_string_or("interface", c.interface);
  if (c.interface.empty() || c.interface.size() >= IFNAMSIZ) {
    m.fail("interface", "must be an interface name of 1 to " + std::to_string(IFNAMSIZ - 1) + " characters");
  }
  for (const char ch : c.interface) {
    if (ch == '/' || ch == ':' || ch == ' ' || ch == '\t') {
      m.fail("interface", "an interface name may not contain '/', ':' or white space");
    }
  }
  c.candump_file = m.get_string_or("candump_file", "");
  read_params(m, can_bridge_params(), c);
  m.finish();
  return c;
}

}  // namespace nimble::can
