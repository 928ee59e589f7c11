#pragma once
/// Private network namespaces for LCM multicast runs.
///
/// LCM's udpm provider needs a loopback that accepts multicast and a route for
/// 224.0.0.0/4. Hosts rarely have that set up, and two runs on one host would hear each
/// other. The launcher therefore moves itself (before it starts any thread or child) into
/// a new network namespace whose loopback it configures; its children inherit it.

#include <memory>
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

/// A second host of a run, emulated: a new network namespace joined to the current one by a
/// veth pair, as two machines by a cable. Each end has its address, multicast on and the
/// 224.0.0.0/4 route (on the veth, not on lo: a datagram sent with ttl >= 1 goes out on the
/// link, and IP_MULTICAST_LOOP, on in LCM, still delivers it to the sender's own host).
///
/// The veth keeps the kernel's default MTU, 1500 bytes, as on an Ethernet lab network: a large
/// LCM message is fragmented on the link as it would be there.
///
/// Nothing outside holds the namespace but this object's descriptor and the processes started
/// in it: once both are gone the kernel frees the namespace, and with it the veth pair (both
/// ends: deleting one end of a veth deletes its peer), so a run leaves nothing behind.
class HostLink {
 public:
  HostLink(const HostLink&) = delete;
  HostLink& operator=(const HostLink&) = delete;
  ~HostLink();

  /// Creates the namespace and the link from the current network namespace, whose end gets
  /// `local_address` ("10.76.67.1/30"), the new one's `remote_address`. The caller must be
  /// single-threaded (it enters the new namespace for a moment) and able to create namespaces
  /// and interfaces (root, or the user namespace enter_private_network_namespace made).
  /// Returns nullptr with `problem` set if any step fails.
  static std::unique_ptr<HostLink> create(const std::string& local_address, const std::string& remote_address,
                                          std::string* problem);

  /// A descriptor of the new host's network namespace (close-on-exec), for setns(2).
  int remote_namespace_fd() const { return remote_fd_; }
  /// The namespace's identity as the kernel names it, e.g. "net:[4026532417]".
  const std::string& remote_namespace_id() const { return remote_id_; }
  /// "veth rig-host0 10.76.67.1/30 <-> rig-host1 10.76.67.2/30, route 224.0.0.0/4 on each end".
  const std::string& detail() const { return detail_; }

  /// The interface names of the two ends (local, remote).
  static constexpr const char* kLocalInterface = "rig-host0";
  static constexpr const char* kRemoteInterface = "rig-host1";

 private:
  HostLink() = default;
  int remote_fd_ = -1;
  std::string remote_id_;
  std::string detail_;
};

/// The exact commands that make the host's loopback carry LCM multicast.
std::string multicast_fix_commands();

}  // namespace nimble::launcher
