#include "foxglove/foxglove_server.h"

#include <sys/resource.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <array>
#include <cerrno>
#include <cstring>
#include <atomic>
#include <chrono>
#include <deque>
#include <filesystem>
#include <functional>
#include <mutex>
#include <optional>
#include <stdexcept>
#include <thread>
#include <utility>

#include <boost/asio/post.hpp>
#include <boost/asio/strand.hpp>

#include "core/descriptors.h"
#include "foxglove/server_impl.h"

namespace nimble::foxglove {

namespace {

/// A frame waiting in a client's queue.
struct Frame {
  std::string data;
  bool text = false;
  bool message = false;  ///< a messageData frame (counted as a message when sent)
  bool backlog = false;  ///< of a backlog (deliver_backlog()): bounded by max_backlog_bytes, not the queue's bounds
};

}  // namespace

std::string endpoint_text(const tcp::endpoint& e) {
  const auto a = e.address();
  return (a.is_v6() ? "[" + a.to_string() + "]" : a.to_string()) + ":" + std::to_string(e.port());
}

/// One WebSocket client.
class WsSession : public std::enable_shared_from_this<WsSession> {
 public:
  WsSession(FoxgloveServer::Impl* server, beast::tcp_stream stream, std::string subprotocol, uint64_t id)
      : server_(server),
        ws_(std::move(stream)),
        subprotocol_(std::move(subprotocol)),
        id_(id),
        session_([server](uint32_t channel) { return server->channel_exists(channel); }) {
    address_ = endpoint_text(beast::get_lowest_layer(ws_).socket().remote_endpoint(ignored_));
  }

  /// Completes the handshake of `request` (whose subprotocol was checked).
  void accept(http::request<http::string_body> request) {
    websocket::stream_base::timeout timeouts{};
    timeouts.handshake_timeout = std::chrono::seconds(30);
    timeouts.idle_timeout = websocket::stream_base::none();
    timeouts.keep_alive_pings = false;
    beast::get_lowest_layer(ws_).expires_never();
    ws_.set_option(timeouts);
    ws_.read_message_max(server_->options.max_frame_bytes);
    ws_.auto_fragment(false);
    const std::string sub = subprotocol_;
    ws_.set_option(websocket::stream_base::decorator([sub](websocket::response_type& res) {
      res.set(http::field::sec_websocket_protocol, sub);
      res.set(http::field::server, "nimble_rig foxglove");
    }));
    ws_.async_accept(request, [self = shared_from_this()](beast::error_code ec) { self->on_accept(ec); });
  }

  /// Queues a messageData frame if this client subscribes to `channel`; drops it when the
  /// queue is full. Any thread.
  void offer(uint32_t channel, uint64_t timestamp_ns, std::string_view payload) {
    std::lock_guard<std::mutex> lock(mu_);
    if (closed_) return;
    const auto it = subs_by_channel_.find(channel);
    if (it == subs_by_channel_.end()) return;
    if (!held_.empty() && held_.count(channel) != 0) return;  // its backlog will hold this message
    const std::size_t size = kMessageDataHeader + payload.size();
    const ServerOptions& o = server_->options;
    if (data_bytes_ + size > o.max_queue_bytes || data_count_ + 1 > o.max_queue_messages) {
      ++dropped_;
      server_->dropped.fetch_add(1, std::memory_order_relaxed);
      return;
    }
    Frame f;
    f.data = message_data(it->second, timestamp_ns, payload);
    f.message = true;
    data_bytes_ += size;
    ++data_count_;
    queue_.push_back(std::move(f));
    kick_locked();
  }

  /// Queues a text frame (serverInfo, advertise, status): never dropped, but a client that lets
  /// them pile up beyond twice the queue's bound is closed. Any thread.
  void send_text(std::string text) {
    std::lock_guard<std::mutex> lock(mu_);
    if (closed_) return;
    control_bytes_ += text.size();
    if (control_bytes_ > 2 * server_->options.max_queue_bytes) {
      closed_ = true;
      net::post(ws_.get_executor(), [self = shared_from_this()] { self->hard_close(); });
      return;
    }
    Frame f;
    f.data = std::move(text);
    f.text = true;
    queue_.push_back(std::move(f));
    kick_locked();
  }

  /// Whether the subscription to `channel` is held as `token`. Any thread.
  bool holds(uint32_t channel, uint64_t token) const {
    std::lock_guard<std::mutex> lock(mu_);
    const auto it = held_.find(channel);
    return !closed_ && it != held_.end() && it->second == token;
  }

  /// Queues the backlog of the held subscription (`channel`, `token`) and releases it: the
  /// newest messages that fit max_backlog_bytes, the older ones dropped and counted. Any thread.
  bool deliver(uint32_t channel, uint64_t token, const std::vector<FoxgloveServer::BacklogMessage>& messages) {
    std::lock_guard<std::mutex> lock(mu_);
    const auto held = held_.find(channel);
    if (closed_ || held == held_.end() || held->second != token) return false;
    held_.erase(held);
    const uint32_t sub = subs_by_channel_.at(channel);  // held only while subscribed
    std::size_t first = messages.size(), bytes = 0;
    while (first > 0) {
      const std::size_t size = kMessageDataHeader + messages[first - 1].payload.size();
      if (backlog_bytes_ + bytes + size > server_->options.max_backlog_bytes) break;
      bytes += size;
      --first;
    }
    if (first > 0) {
      dropped_ += static_cast<int64_t>(first);
      server_->dropped.fetch_add(static_cast<int64_t>(first), std::memory_order_relaxed);
    }
    for (std::size_t i = first; i < messages.size(); ++i) {
      Frame f;
      f.data = message_data(sub, messages[i].timestamp_ns, messages[i].payload);
      f.message = true;
      f.backlog = true;
      queue_.push_back(std::move(f));
    }
    backlog_bytes_ += bytes;
    if (first < messages.size()) kick_locked();
    return true;
  }

  uint64_t id() const { return id_; }

  /// Asks for a clean close once the queue is written. Any thread.
  void close() {
    net::post(ws_.get_executor(), [self = shared_from_this()] {
      std::lock_guard<std::mutex> lock(self->mu_);
      self->close_requested_ = true;
      self->kick_locked();
    });
  }

  /// Closes the socket at once. Any thread.
  void abort() {
    net::post(ws_.get_executor(), [self = shared_from_this()] { self->hard_close(); });
  }

  ClientStats stats() const {
    std::lock_guard<std::mutex> lock(mu_);
    return ClientStats{id_, address_, subprotocol_, subs_by_channel_.size(), sent_, dropped_};
  }

 private:
  void on_accept(beast::error_code ec) {
    if (ec) return;  // the client went away during its handshake
    server_->add_session(shared_from_this());
    accepted_ = true;
    send_text(server_info_json(server_->options.name, server_->session_id, server_->options.metadata));
    const std::vector<Channel> channels = server_->channel_list();
    if (!channels.empty()) send_text(advertise_json(channels));
    do_read();
  }

  void do_read() {
    ws_.async_read(buffer_, [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

  void on_read(beast::error_code ec) {
    if (ec) {
      if (ec == websocket::error::message_too_big) {
        server_->oversized_closes.fetch_add(1);
        server_->protocol_errors.fetch_add(1);
      }
      finish();
      return;
    }
    const std::string_view frame(static_cast<const char*>(buffer_.data().data()), buffer_.size());
    std::vector<std::string> replies;
    const SessionCounters before = session_.counters();
    std::vector<FoxgloveServer::NewSubscription> added;
    if (ws_.got_text()) {
      const std::vector<uint32_t> changed = session_.on_text(frame, &replies);
      if (!changed.empty()) added = update_subscriptions(changed);
    } else {
      session_.on_binary(frame, &replies);
    }
    buffer_.consume(buffer_.size());
    server_->refused.fetch_add(session_.counters().refused - before.refused);
    server_->protocol_errors.fetch_add(session_.counters().protocol_errors - before.protocol_errors);
    for (auto& r : replies) send_text(std::move(r));
    for (const auto& s : added) server_->announce(s);
    do_read();
  }

  /// Mirrors the session's subscriptions for offer() and the server's per-channel counts.
  /// Returns the new subscriptions it holds (while the server has a subscribe handler).
  std::vector<FoxgloveServer::NewSubscription> update_subscriptions(const std::vector<uint32_t>& changed) {
    std::vector<FoxgloveServer::NewSubscription> added;
    const bool hold = server_->hold_subscriptions.load();
    std::lock_guard<std::mutex> lock(mu_);
    for (uint32_t channel : changed) {
      uint32_t sub = 0;
      const bool now = session_.subscription_of(channel, &sub);
      const auto old = subs_by_channel_.find(channel);
      const bool was = old != subs_by_channel_.end();
      const bool fresh = now && (!was || old->second != sub);
      if (now)
        subs_by_channel_[channel] = sub;
      else
        subs_by_channel_.erase(channel);
      if (now && !was) server_->subscribers[channel].fetch_add(1);
      if (!now && was) server_->subscribers[channel].fetch_sub(1);
      if (!now) held_.erase(channel);
      if (fresh && hold) {
        const uint64_t token = server_->next_token.fetch_add(1);
        held_[channel] = token;
        added.push_back(FoxgloveServer::NewSubscription{id_, channel, token});
      } else if (fresh) {
        held_.erase(channel);
      }
    }
    return added;
  }

  /// Starts writing the queue's front if nothing is being written. Under mu_.
  void kick_locked() {
    if (writing_) return;
    writing_ = true;
    net::post(ws_.get_executor(), [self = shared_from_this()] { self->do_write(); });
  }

  void do_write() {
    Frame* front = nullptr;
    {
      std::lock_guard<std::mutex> lock(mu_);
      if (queue_.empty() || write_failed_) {
        writing_ = false;
        if (close_requested_ && !closing_ && !write_failed_) {
          closing_ = true;
          writing_ = true;
          ws_.async_close(websocket::close_code::normal,
                          [self = shared_from_this()](beast::error_code) { self->hard_close(); });
        }
        return;
      }
      front = &queue_.front();  // a deque keeps its elements in place while others are added
    }
    ws_.text(front->text);
    ws_.async_write(net::buffer(front->data),
                    [self = shared_from_this()](beast::error_code ec, std::size_t n) { self->on_write(ec, n); });
  }

  void on_write(beast::error_code ec, std::size_t bytes) {
    {
      std::lock_guard<std::mutex> lock(mu_);
      Frame& f = queue_.front();
      if (f.backlog) {
        backlog_bytes_ -= f.data.size();
      } else if (f.message) {
        data_bytes_ -= f.data.size();
        --data_count_;
      }
      if (f.message) {
        if (!ec) {
          ++sent_;
          server_->messages_sent.fetch_add(1, std::memory_order_relaxed);
        }
      } else {
        control_bytes_ -= f.data.size();
      }
      queue_.pop_front();
      if (ec) write_failed_ = true;
    }
    if (!ec) server_->bytes_sent.fetch_add(static_cast<int64_t>(bytes), std::memory_order_relaxed);
    if (ec) {
      hard_close();
      return;
    }
    do_write();
  }

  void hard_close() {
    beast::error_code ignored;
    beast::get_lowest_layer(ws_).socket().shutdown(tcp::socket::shutdown_both, ignored);
    beast::get_lowest_layer(ws_).socket().close(ignored);
  }

  /// The connection ended (read failed): unregisters the client.
  void finish() {
    {
      std::lock_guard<std::mutex> lock(mu_);
      closed_ = true;
      for (const auto& kv : subs_by_channel_) server_->subscribers[kv.first].fetch_sub(1);
      subs_by_channel_.clear();
      held_.clear();
      queue_.erase(queue_.begin() + (writing_ && !queue_.empty() ? 1 : 0), queue_.end());
    }
    if (accepted_) {
      accepted_ = false;
      server_->remove_session(this);
    }
    hard_close();
  }

  FoxgloveServer::Impl* server_;  // outlives every connection: its io_context owns them
  websocket::stream<beast::tcp_stream> ws_;
  std::string subprotocol_, address_;
  uint64_t id_;
  beast::error_code ignored_;
  beast::flat_buffer buffer_;
  ClientSession session_;  // I/O thread only
  bool accepted_ = false;  // I/O thread only

  mutable std::mutex mu_;  // everything below
  std::map<uint32_t, uint32_t> subs_by_channel_;
  std::map<uint32_t, uint64_t> held_;  // channel -> token of its held subscription
  std::deque<Frame> queue_;
  std::size_t data_bytes_ = 0, data_count_ = 0, control_bytes_ = 0, backlog_bytes_ = 0;
  bool writing_ = false, closed_ = false, close_requested_ = false, closing_ = false, write_failed_ = false;
  int64_t sent_ = 0, dropped_ = 0;
};

void start_websocket(FoxgloveServer::Impl* server, beast::tcp_stream stream, const std::string& subprotocol,
                     uint64_t id, http::request<http::string_body> request) {
  std::make_shared<WsSession>(server, std::move(stream), subprotocol, id)->accept(std::move(request));
}

void FoxgloveServer::Impl::do_accept() {
  acceptor.async_accept(net::make_strand(ioc), [self = this](beast::error_code ec, tcp::socket s) {
    if (ec) {
      if (ec == net::error::operation_aborted || !self->acceptor.is_open()) return;
    } else {
      self->on_connection(std::move(s));
    }
    self->do_accept();
  });
}

void FoxgloveServer::Impl::on_connection(tcp::socket socket) {
  set_close_on_exec(socket.native_handle());
  beast::error_code ignored;
  socket.set_option(tcp::no_delay(true), ignored);
  start_http_connection(this, std::move(socket));
}

void FoxgloveServer::Impl::add_session(const std::shared_ptr<WsSession>& s) {
  std::lock_guard<std::mutex> lock(sessions_mu);
  sessions.push_back(s);
  clients_now.fetch_add(1);
  clients_total.fetch_add(1);
}

void FoxgloveServer::Impl::remove_session(const WsSession* s) {
  std::lock_guard<std::mutex> lock(sessions_mu);
  for (auto it = sessions.begin(); it != sessions.end(); ++it) {
    if (it->get() == s) {
      sessions.erase(it);
      clients_now.fetch_sub(1);
      return;
    }
  }
}

std::shared_ptr<WsSession> FoxgloveServer::Impl::find_session(uint64_t client) const {
  std::lock_guard<std::mutex> lock(sessions_mu);
  for (const auto& s : sessions) {
    if (s->id() == client) return s;
  }
  return nullptr;
}

void FoxgloveServer::Impl::announce(const FoxgloveServer::NewSubscription& s) {
  {
    std::lock_guard<std::mutex> lock(handler_mu);
    if (subscribe_handler) {
      subscribe_handler(s);
      return;
    }
  }
  if (auto session = find_session(s.client)) session->deliver(s.channel, s.token, {});
}

FoxgloveServer::FoxgloveServer(ServerOptions options) : impl_(std::make_unique<Impl>()) {
  impl_->options = std::move(options);
  const ServerOptions& o = impl_->options;
  if (!o.web_root.empty()) {
    std::error_code fec;
    impl_->web_root = std::filesystem::canonical(o.web_root, fec);
    if (fec || !std::filesystem::is_directory(impl_->web_root, fec)) {
      throw std::invalid_argument("web root " + o.web_root + " is not a directory");
    }
  }
  if (o.max_queue_bytes == 0 || o.max_queue_messages == 0 || o.max_frame_bytes == 0) {
    throw std::invalid_argument("the queue and frame bounds must be positive");
  }
  beast::error_code ec;
  net::ip::address address = net::ip::make_address(o.host == "localhost" ? "127.0.0.1" : o.host, ec);
  if (ec) throw std::invalid_argument("'" + o.host + "' is not an IP address (e.g. 127.0.0.1, 0.0.0.0, ::1)");
  const tcp::endpoint endpoint(address, o.port);
  const std::string where = endpoint_text(endpoint);
  auto& acc = impl_->acceptor;
  acc.open(endpoint.protocol(), ec);
  // A process the rig starts does not inherit the listening socket (nor, below, a client's).
  if (!ec && !set_close_on_exec(acc.native_handle())) ec = beast::error_code(errno, beast::system_category());
  if (!ec) acc.set_option(net::socket_base::reuse_address(true), ec);
  if (!ec) acc.bind(endpoint, ec);
  if (!ec) acc.listen(net::socket_base::max_listen_connections, ec);
  if (ec) throw std::runtime_error("cannot listen on " + where + ": " + ec.message());
  impl_->port = acc.local_endpoint().port();
  const net::ip::address bound = acc.local_endpoint().address();
  impl_->loopback = bound.is_loopback() || (bound.is_v6() && bound.to_v6().is_v4_mapped() &&
                                            net::ip::make_address_v4(net::ip::v4_mapped, bound.to_v6()).is_loopback());
  impl_->session_id = std::to_string(std::chrono::duration_cast<std::chrono::milliseconds>(
                                         std::chrono::system_clock::now().time_since_epoch())
                                         .count()) +
                      "-" + std::to_string(impl_->port);
}

FoxgloveServer::~FoxgloveServer() { stop(); }

uint16_t FoxgloveServer::port() const { return impl_->port; }
const std::string& FoxgloveServer::host() const { return impl_->options.host; }
bool FoxgloveServer::loopback() const { return impl_->loopback; }
std::string FoxgloveServer::url() const {
  const std::string& h = impl_->options.host;
  return "ws://" + (h.find(':') != std::string::npos ? "[" + h + "]" : h) + ":" + std::to_string(impl_->port);
}

void FoxgloveServer::start() {
  if (impl_->running.exchange(true)) return;
  impl_->do_accept();
  impl_->thread = std::thread([impl = impl_.get()] {
    set_thread_nice(impl->options.thread_nice);
    impl->ioc.run();
  });
}

void FoxgloveServer::stop() {
  if (!impl_->running.exchange(false)) return;
  // Every client gets a WebSocket close after what is queued for it; then the thread ends.
  net::post(impl_->ioc, [impl = impl_.get()] {
    beast::error_code ignored;
    impl->acceptor.close(ignored);
    std::lock_guard<std::mutex> lock(impl->sessions_mu);
    for (auto& s : impl->sessions) s->close();
  });
  const auto wait = [this](int ms) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(ms);
    while (impl_->clients_now.load() > 0 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
  };
  wait(500);
  // A client that did not answer the close (not reading) has its connection closed under it.
  net::post(impl_->ioc, [impl = impl_.get()] {
    std::lock_guard<std::mutex> lock(impl->sessions_mu);
    for (auto& s : impl->sessions) s->abort();
  });
  wait(100);
  impl_->ioc.stop();
  impl_->thread.join();
  std::lock_guard<std::mutex> lock(impl_->sessions_mu);
  impl_->sessions.clear();
}

uint32_t FoxgloveServer::add_channel(const std::string& topic, const std::string& schema_name,
                                     const std::string& schema) {
  Channel c;
  {
    std::lock_guard<std::mutex> lock(impl_->channels_mu);
    if (impl_->channels.size() >= kMaxChannels) {
      throw std::length_error("at most " + std::to_string(kMaxChannels) + " channels");
    }
    c = Channel{static_cast<uint32_t>(impl_->channels.size() + 1), topic, schema_name, schema};
    impl_->channels.push_back(c);
  }
  const std::string advertise = advertise_json({c});
  std::lock_guard<std::mutex> lock(impl_->sessions_mu);
  for (auto& s : impl_->sessions) s->send_text(advertise);
  return c.id;
}

bool FoxgloveServer::has_subscribers(uint32_t channel_id) const {
  return channel_id <= kMaxChannels && impl_->subscribers[channel_id].load(std::memory_order_relaxed) > 0;
}

void FoxgloveServer::set_subscribe_handler(std::function<void(const NewSubscription&)> handler) {
  std::lock_guard<std::mutex> lock(impl_->handler_mu);
  impl_->hold_subscriptions.store(static_cast<bool>(handler));
  impl_->subscribe_handler = std::move(handler);
}

bool FoxgloveServer::holds(const NewSubscription& s) const {
  const auto session = impl_->find_session(s.client);
  return session && session->holds(s.channel, s.token);
}

bool FoxgloveServer::deliver_backlog(const NewSubscription& s, const std::vector<BacklogMessage>& messages) {
  const auto session = impl_->find_session(s.client);
  return session && session->deliver(s.channel, s.token, messages);
}

void FoxgloveServer::publish(uint32_t channel_id, uint64_t timestamp_ns, std::string_view payload) {
  if (!has_subscribers(channel_id)) return;
  std::lock_guard<std::mutex> lock(impl_->sessions_mu);
  for (auto& s : impl_->sessions) s->offer(channel_id, timestamp_ns, payload);
}

void FoxgloveServer::broadcast_status(StatusLevel level, const std::string& message) {
  const std::string text = status_json(level, message);
  std::lock_guard<std::mutex> lock(impl_->sessions_mu);
  for (auto& s : impl_->sessions) s->send_text(text);
}

ServerStats FoxgloveServer::stats() const {
  const Impl& i = *impl_;
  ServerStats s;
  s.clients_now = i.clients_now.load();
  s.clients_total = i.clients_total.load();
  s.handshakes_refused = i.handshakes_refused.load();
  s.messages_sent = i.messages_sent.load();
  s.bytes_sent = i.bytes_sent.load();
  s.dropped = i.dropped.load();
  s.refused = i.refused.load();
  s.protocol_errors = i.protocol_errors.load();
  s.oversized_closes = i.oversized_closes.load();
  s.http_requests = i.http_requests.load();
  return s;
}

std::vector<ClientStats> FoxgloveServer::clients() const {
  std::vector<ClientStats> out;
  std::lock_guard<std::mutex> lock(impl_->sessions_mu);
  for (const auto& s : impl_->sessions) out.push_back(s->stats());
  return out;
}

std::string set_thread_nice(int nice) {
  if (nice == 0) return "";
  const auto tid = static_cast<id_t>(::syscall(SYS_gettid));
  if (::setpriority(PRIO_PROCESS, tid, nice) != 0) return std::strerror(errno);
  return "";
}

void parse_host_port(const std::string& text, const std::string& default_host, std::string* host, uint16_t* port) {
  std::string h = default_host, p = text;
  if (!text.empty() && text[0] == '[') {
    const std::size_t close = text.find(']');
    if (close == std::string::npos || close + 1 >= text.size() || text[close + 1] != ':') {
      throw std::invalid_argument("'" + text + "' is not [HOST]:PORT");
    }
    h = text.substr(1, close - 1);
    p = text.substr(close + 2);
  } else if (const std::size_t colon = text.rfind(':'); colon != std::string::npos) {
    if (text.find(':') != colon) {
      throw std::invalid_argument("'" + text + "': write an IPv6 host in brackets, [::1]:8765");
    }
    h = text.substr(0, colon);
    p = text.substr(colon + 1);
  }
  if (h.empty()) throw std::invalid_argument("'" + text + "' has an empty host");
  if (p.empty() || p.size() > 5 || p.find_first_not_of("0123456789") != std::string::npos || std::stoul(p) > 65535) {
    throw std::invalid_argument("'" + text + "': the port must be a number from 0 to 65535 ([HOST:]PORT)");
  }
  *host = h;
  *port = static_cast<uint16_t>(std::stoul(p));
}

}  // namespace nimble::foxglove
