#pragma once
/// The inside of FoxgloveServer, shared by its two sides: the WebSocket sessions and the server
/// itself (foxglove_server.cc), and the plain HTTP connection that comes first on every socket
/// and serves the page's files (http_connection.cc). Not for use outside foxglove/.

#include <array>
#include <atomic>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>

#include "foxglove/foxglove_server.h"

namespace nimble::foxglove {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;

class WsSession;

struct FoxgloveServer::Impl {
  ServerOptions options;
  net::io_context ioc{1};
  tcp::acceptor acceptor{ioc};
  std::thread thread;
  std::atomic<bool> running{false};
  std::string session_id;
  uint16_t port = 0;
  bool loopback = false;
  std::filesystem::path web_root;  // canonical; empty: no files served

  mutable std::mutex channels_mu;
  std::vector<Channel> channels;  // id i + 1 at index i
  std::array<std::atomic<int>, kMaxChannels + 1> subscribers{};

  mutable std::mutex sessions_mu;
  std::vector<std::shared_ptr<WsSession>> sessions;
  uint64_t next_client_id = 1;

  // New subscriptions are held while a handler is set (set_subscribe_handler()).
  std::mutex handler_mu;
  std::function<void(const FoxgloveServer::NewSubscription&)> subscribe_handler;  // under handler_mu
  std::atomic<bool> hold_subscriptions{false};
  std::atomic<uint64_t> next_token{1};

  std::atomic<int64_t> clients_now{0}, clients_total{0}, handshakes_refused{0}, messages_sent{0}, bytes_sent{0},
      dropped{0}, refused{0}, protocol_errors{0}, oversized_closes{0}, http_requests{0};

  bool channel_exists(uint32_t id) const {
    std::lock_guard<std::mutex> lock(channels_mu);
    return id >= 1 && id <= channels.size();
  }
  std::vector<Channel> channel_list() const {
    std::lock_guard<std::mutex> lock(channels_mu);
    return channels;
  }

  void do_accept();
  void on_connection(tcp::socket socket);
  void add_session(const std::shared_ptr<WsSession>& s);
  void remove_session(const WsSession* s);
  std::shared_ptr<WsSession> find_session(uint64_t client) const;
  /// Tells the handler of a held subscription; releases it at once if there is none any more.
  void announce(const FoxgloveServer::NewSubscription& s);
};

/// "127.0.0.1:8765", "[::1]:8765".
std::string endpoint_text(const tcp::endpoint& e);

/// Reads one HTTP request from a new connection: a WebSocket upgrade becomes a session
/// (start_websocket()), anything else is answered from the web root and closed.
void start_http_connection(FoxgloveServer::Impl* server, tcp::socket socket);

/// A WebSocket session for `request`, an upgrade offering `subprotocol`, as client `id`.
void start_websocket(FoxgloveServer::Impl* server, beast::tcp_stream stream, const std::string& subprotocol,
                     uint64_t id, http::request<http::string_body> request);

}  // namespace nimble::foxglove
