#pragma once
/// Kernel-side channel filter for LCM's UDP multicast receive socket.
///
/// LCM 1.3.1's udpm provider joins one multicast group per URL: every process of a run
/// receives every message of the run, and its receive thread wakes for each one only to drop
/// the channels nobody in the process subscribed. With the rig's ~6,000 messages per second
/// and five receivers, most wake-ups carry nothing for the process, and they delay the ones
/// that do (docs/timing.md "Timing").
///
/// A classic BPF socket filter (SO_ATTACH_FILTER) on the provider's receive socket drops those
/// datagrams in the kernel instead. It reads the LCM short-message header
/// (magic "LC02", sequence number, NUL-terminated channel name) and keeps only the listed
/// channels; anything else (fragmented messages, other magics) passes unchanged, so the filter
/// can only remove messages LCM itself would have dropped. LCM_SELF_TEST, the provider's
/// start-up probe, always passes.

#include <linux/filter.h>

#include <set>
#include <string>
#include <vector>

namespace nimble::transport {

/// Byte offset of the LCM header in what a UDP socket filter sees (the UDP header comes first).
constexpr unsigned kLcmHeaderOffset = 8;

/// The filter program keeping `channels` (exact names) and every datagram that is not an LCM
/// short message.
std::vector<sock_filter> channel_filter_program(const std::set<std::string>& channels);

/// Attaches the program for `channels` to socket `fd` (replacing any filter before).
/// Returns "" on success, else why not.
std::string attach_channel_filter(int fd, const std::set<std::string>& channels);

/// Removes the filter from socket `fd`, so that every datagram reaches it again (a subscription
/// by pattern needs them all). Returns "" on success, else why not.
std::string detach_channel_filter(int fd);

/// UDP sockets of this process bound to `port` (the receive sockets of LCM udpm instances).
std::set<int> udp_sockets_bound_to(int port);

/// The port of a udpm:// URL (7667 if none is given), or -1 for another provider.
int udpm_port(const std::string& url);

/// LCM's UDP short message, as the udpm provider sends it (for tests).
std::vector<unsigned char> lcm_short_datagram(const std::string& channel, const std::vector<unsigned char>& payload,
                                              unsigned seqno = 0);

}  // namespace nimble::transport
