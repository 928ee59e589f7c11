#pragma once
/// Private network namespaces for LCM multicast runs.
///
/// LCM's udpm provider needs a loopback that accepts multicast and a route for
/// 224.0.0.0/4. Hosts rarely have that set up, and two runs on one host would hear each
/// other. The launcher therefore moves itself (before it starts any thread or child) into
/// a new network namespace whose loopback it configures; its children inherit it.

#include <string>

namespace nimble::launcher {

/// Result of trying to enter a private network namespace.
struct NamespaceResult {
  bool ok = false;
  std::string detail;  ///< what was done, or why it failed
};

/// Unshares the network namespace of the calling (single-threaded) process - as root
/// directly, otherwise through a user namespace - and brings up the loopback with
/// multicast and a 224.0.0.0/4 route.
NamespaceResult enter_private_network_namespace();

/// Brings up `lo` with multicast and adds the 224.0.0.0/4 route (in the current namespace).
NamespaceResult configure_loopback_multicast();

/// True if LCM can open `url` in the current namespace (creates and destroys an instance).
bool lcm_url_works(const std::string& url);

/// Makes sure the CAN interface `name` exists and is up in the current network namespace;
/// a missing one is created as a virtual CAN interface (`ip link add dev NAME type vcan`)
/// when `create_virtual`. With `fd` (CAN FD) a vcan created here gets the CAN FD MTU (72), and an
/// existing interface with the classical MTU (16) is an error naming the `ip link set` fix.
/// Returns "" on success, else what is wrong and how to fix it (a kernel without CAN support is
/// named as such).
std::string ensure_can_interface(const std::string& name, bool create_virtual, bool fd = false);

/// The exact commands that make the host's loopback carry LCM multicast.
std::string multicast_fix_commands();

}  // namespace nimble::launcher
