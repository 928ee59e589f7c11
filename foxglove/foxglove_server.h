#pragma once
/// A read-only Foxglove WebSocket server (Boost.Beast): Foxglove and Lichtblick connect to it
/// ("Open connection" -> "Foxglove WebSocket" -> ws://127.0.0.1:8765) and subscribe to the
/// channels it advertises, JSON messages with a JSON Schema each.
///
/// One I/O thread serves every client. publish() may be called from any thread and never waits
/// for a client: it copies the message into the queue of each client subscribed to the channel,
/// a queue bounded in bytes and in messages; a message that does not fit is dropped for that
/// client and counted. A client that does not read therefore costs the publisher nothing but
/// its drops.
///
/// A new subscription may be held (set_subscribe_handler): publish() leaves it out until the
/// publisher hands it the messages that came before (deliver_backlog()), so that a client that
/// subscribes late gets a channel's recent past first, then the live messages, without gap,
/// repetition or reordering.
///
/// The protocol itself (handshake subprotocols, the messages, one client's subscriptions) is in
/// protocol.h; this file adds the sockets. The same port optionally serves static files over
/// plain HTTP GET and HEAD (a dashboard page): a request that is not a WebSocket upgrade gets a
/// file of `web_root` by the rules of web_path.h (only regular files beneath the canonical root,
/// by a fixed table of types; 400 for a malformed target, 404 for anything else not served, 405
/// for another method).

#include <cstddef>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "foxglove/protocol.h"

namespace nimble::foxglove {

struct ServerOptions {
  std::string host = "127.0.0.1";               ///< the address to listen on (an IPv4 or IPv6 literal, or "localhost")
  uint16_t port = 8765;                         ///< 0: a free port, chosen by the system (port() tells which)
  std::string name = "nimble_rig";              ///< serverInfo's name
  std::map<std::string, std::string> metadata;  ///< serverInfo's metadata
  /// Each client's queue of messages not yet sent: at most this many bytes and this many
  /// messages; a message beyond either is dropped for that client and counted.
  std::size_t max_queue_bytes = 8u << 20;
  std::size_t max_queue_messages = 8192;
  /// Backlogs (deliver_backlog()) waiting in a client's queue: at most this many bytes, beyond
  /// the bounds above (a backlog is bounded by its publisher, e.g. 10 s of a channel); the
  /// oldest messages of a backlog that does not fit are dropped and counted.
  std::size_t max_backlog_bytes = 64u << 20;
  /// A client frame larger than this closes the connection (close code 1009, too big).
  std::size_t max_frame_bytes = 64u << 10;
  /// A directory served over HTTP GET and HEAD on the same port ("/" is index.html; web_path.h
  /// says what is served); "": none.
  std::string web_root;
  /// The nice value of the I/O thread (0: as the thread that calls start()); a live view of a
  /// real-time run yields the CPU to the rig's processes.
  int thread_nice = 0;
};

/// Sets the calling thread's nice value to `nice` (Linux: nice is per thread); 0 does nothing.
/// Returns "" or why it could not.
std::string set_thread_nice(int nice);

/// The server's figures since it was made.
struct ServerStats {
  int64_t clients_now = 0;
  int64_t clients_total = 0;       ///< WebSocket clients accepted
  int64_t handshakes_refused = 0;  ///< upgrades offering no subprotocol of the protocol
  int64_t messages_sent = 0;       ///< messageData frames written to clients
  int64_t bytes_sent = 0;          ///< bytes of every frame written (messages, serverInfo, advertise, status)
  int64_t dropped = 0;             ///< messages dropped because a client's queue was full
  int64_t refused = 0;             ///< client messages refused (read-only server), binary frames
  int64_t protocol_errors = 0;     ///< bad client messages (garbage, unknown op, unknown ids, oversized)
  int64_t oversized_closes = 0;    ///< connections closed for a frame over max_frame_bytes
  int64_t http_requests = 0;       ///< plain HTTP requests answered
};

/// One connected client's figures.
struct ClientStats {
  uint64_t id = 0;          ///< the server's number for it (1, 2, ...)
  std::string address;      ///< "127.0.0.1:41234"
  std::string subprotocol;  ///< the one agreed
  std::size_t subscriptions = 0;
  int64_t messages_sent = 0;
  int64_t dropped = 0;
};

class FoxgloveServer {
 public:
  /// Listens on options.host:options.port (nothing is served before start()).
  /// @throws std::invalid_argument for a bad option (host that is not an address, a web root
  ///         that is not a directory), std::runtime_error naming the address if it cannot be bound.
  explicit FoxgloveServer(ServerOptions options);
  /// stop().
  ~FoxgloveServer();
  FoxgloveServer(const FoxgloveServer&) = delete;
  FoxgloveServer& operator=(const FoxgloveServer&) = delete;

  /// The port bound (the one chosen when options.port was 0).
  uint16_t port() const;
  const std::string& host() const;
  /// Whether the address listened on is a loopback one (127.0.0.0/8, ::1, ::ffff:127.x.y.z);
  /// false for 0.0.0.0, :: and any other address, which other machines may reach.
  bool loopback() const;
  /// "ws://127.0.0.1:8765".
  std::string url() const;

  /// Starts the I/O thread. The listening socket exists from the constructor on, so a caller
  /// may bind first and start the thread later (e.g. after moving into another network
  /// namespace: the socket stays where it was made).
  void start();
  /// Closes every connection (a WebSocket close, or at worst the socket) and ends the thread.
  void stop();

  /// Adds a channel (JSON messages described by `schema`, a JSON Schema); returns its id
  /// (1, 2, ...). Channels added after start() are advertised to the clients connected.
  /// @throws std::length_error beyond kMaxChannels.
  uint32_t add_channel(const std::string& topic, const std::string& schema_name, const std::string& schema);
  static constexpr uint32_t kMaxChannels = 1024;

  /// Whether some client subscribes to `channel_id` now (one atomic load): a caller can skip
  /// encoding a message that no one would receive.
  bool has_subscribers(uint32_t channel_id) const;
  /// Queues a message of `channel_id` (JSON text) with `timestamp_ns` for every client
  /// subscribed to it. Thread-safe; never waits for a client.
  void publish(uint32_t channel_id, uint64_t timestamp_ns, std::string_view payload);
  /// A client's new subscription to a channel, held until deliver_backlog() names it.
  struct NewSubscription {
    uint64_t client = 0;  ///< ClientStats::id
    uint32_t channel = 0;
    uint64_t token = 0;  ///< this subscription (a later one of the same client and channel has another)
  };
  /// With a handler, every new subscription starts held: publish() leaves that client out for
  /// that channel, and `handler` is called (on the I/O thread, with no lock of the server held;
  /// it must not block) so that the publisher can answer with deliver_backlog(). Without one
  /// (the default, or nullptr), subscriptions get the live messages at once. Set it before
  /// clients subscribe; setting nullptr waits for a call in progress, so that the handler's
  /// owner can go away.
  void set_subscribe_handler(std::function<void(const NewSubscription&)> handler);
  /// Whether the subscription `s` is still held (the client has not unsubscribed or gone).
  bool holds(const NewSubscription& s) const;
  /// One message of a backlog: its timestamp [ns] and JSON text.
  struct BacklogMessage {
    uint64_t timestamp_ns = 0;
    std::string payload;
  };
  /// Queues `messages` (in their order) for the held subscription `s` and releases it: the live
  /// messages that publish() queues from then on follow them. Returns false (and queues
  /// nothing) if `s` is not held any more. Thread-safe; never waits for a client.
  bool deliver_backlog(const NewSubscription& s, const std::vector<BacklogMessage>& messages);

  /// Sends a `status` message to every client.
  void broadcast_status(StatusLevel level, const std::string& message);

  ServerStats stats() const;
  std::vector<ClientStats> clients() const;

  struct Impl;

 private:
  std::unique_ptr<Impl> impl_;
};

/// "[HOST:]PORT" (a host "[::1]:8765" in brackets for IPv6) as host and port; the host defaults
/// to `default_host`. @throws std::invalid_argument naming the text when it is not that.
void parse_host_port(const std::string& text, const std::string& default_host, std::string* host, uint16_t* port);

}  // namespace nimble::foxglove
