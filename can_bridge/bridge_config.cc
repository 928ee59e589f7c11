#include "can_bridge/bridge_config.h"

#include <net/if.h>

namespace nimble::can {

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
  if (m.has("create_virtual")) c.create_virtual = m.get_bool("create_virtual");
  if (m.has("candump_log")) c.candump_log = m.get_bool("candump_log");
  c.candump_file = m.get_string_or("candump_file", "");
  c.health_rate_hz = m.get_double_or("health_rate_hz", c.health_rate_hz, Range::closed(0.1, 50.0));
  if (m.has("receive_buffer_bytes")) {
    c.receive_buffer_bytes = static_cast<int>(m.get_int("receive_buffer_bytes", Range::closed(0, 64 * 1024 * 1024)));
  }
  if (m.has("fd")) c.fd = m.get_bool("fd");
  m.finish();
  return c;
}

}  // namespace nimble::can
