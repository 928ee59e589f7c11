#pragma once
/// The Foxglove WebSocket protocol (subprotocol foxglove.websocket.v1, also offered by newer
/// clients as foxglove.sdk.v1) as this read-only server speaks it, without sockets: the
/// messages it sends, and one client's session (its subscriptions), which takes the client's
/// frames one at a time and answers with the messages to send back. The server
/// (foxglove_server.h) owns the sockets; the unit tests and the fuzz target drive a session
/// directly.
///
/// The server only publishes: it offers no capability (no client publishing, parameters,
/// services, assets, connection graph). Of the client's messages it takes `subscribe` and
/// `unsubscribe`; every other one is refused with a `status` error, and counted.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <string_view>
#include <vector>

#include <nlohmann/json_fwd.hpp>

namespace nimble::foxglove {

/// The subprotocols this server speaks, in order of preference.
inline constexpr const char* kSubprotocolV1 = "foxglove.websocket.v1";
inline constexpr const char* kSubprotocolSdk = "foxglove.sdk.v1";

/// The subprotocol to answer a handshake whose Sec-WebSocket-Protocol header is `offered`
/// (a comma-separated list): the first of the client's that this server speaks, "" if none.
std::string choose_subprotocol(std::string_view offered);

/// One advertised channel: JSON messages described by a JSON Schema.
struct Channel {
  uint32_t id = 0;
  std::string topic;
  std::string schema_name;
  std::string schema;  ///< JSON Schema text
};

/// Status levels of the `status` message.
enum class StatusLevel { kInfo = 0, kWarning = 1, kError = 2 };

/// `serverInfo`: the server's name, no capabilities, `metadata` and `sessionId`.
std::string server_info_json(const std::string& name, const std::string& session_id,
                             const std::map<std::string, std::string>& metadata);
/// `advertise` of `channels` (encoding json, schemaEncoding jsonschema).
std::string advertise_json(const std::vector<Channel>& channels);
/// `unadvertise` of `channel_ids`.
std::string unadvertise_json(const std::vector<uint32_t>& channel_ids);
/// `status` with `level` and `message` (text that is not UTF-8 is replaced, not refused).
std::string status_json(StatusLevel level, const std::string& message);

/// Size of the binary messageData header: opcode 0x01, u32 subscription id, u64 timestamp [ns].
inline constexpr std::size_t kMessageDataHeader = 13;
/// Writes the messageData header (little-endian) to `out[0..12]`.
void write_message_data_header(uint32_t subscription_id, uint64_t timestamp_ns, unsigned char* out);
/// A whole messageData frame.
std::string message_data(uint32_t subscription_id, uint64_t timestamp_ns, std::string_view payload);

/// What a session counted.
struct SessionCounters {
  int64_t refused = 0;          ///< well-formed requests this read-only server does not serve, binary frames
  int64_t protocol_errors = 0;  ///< garbage, invalid JSON, unknown op, bad fields, unknown ids
};

/// One client's state: its subscriptions (client subscription id -> channel id, at most one per
/// channel, as the protocol says). Not thread-safe: the server calls it from its I/O thread.
class ClientSession {
 public:
  /// `channel_exists(id)`: whether the server advertises channel `id`.
  explicit ClientSession(std::function<bool(uint32_t)> channel_exists);

  /// One text frame from the client. Appends to `replies` the text frames to send back (a
  /// `status` error for each thing refused); returns the channels whose subscription changed
  /// (subscribed or unsubscribed), so that the server can update its per-channel counts.
  std::vector<uint32_t> on_text(std::string_view frame, std::vector<std::string>* replies);
  /// One binary frame from the client: always refused (no client publishing, no services).
  void on_binary(std::string_view frame, std::vector<std::string>* replies);

  /// Subscription id of `channel_id` for this client, or false.
  bool subscription_of(uint32_t channel_id, uint32_t* subscription_id) const;
  /// Subscription id -> channel id.
  const std::map<uint32_t, uint32_t>& subscriptions() const { return by_subscription_; }
  const SessionCounters& counters() const { return counters_; }

 private:
  void subscribe(const nlohmann::json& request, std::vector<uint32_t>* changed, std::vector<std::string>* replies);
  void unsubscribe(const nlohmann::json& request, std::vector<uint32_t>* changed, std::vector<std::string>* replies);
  void protocol_error(const std::string& message, std::vector<std::string>* replies);
  void refuse(const std::string& message, std::vector<std::string>* replies);

  std::function<bool(uint32_t)> channel_exists_;
  std::map<uint32_t, uint32_t> by_subscription_;  ///< subscription id -> channel id
  std::map<uint32_t, uint32_t> by_channel_;       ///< channel id -> subscription id
  SessionCounters counters_;
};

}  // namespace nimble::foxglove
