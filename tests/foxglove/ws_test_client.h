#pragma once
/// A Boost.Beast WebSocket client for the Foxglove server's tests: connect with subprotocols,
/// reads bounded in time.

#include <chrono>
#include <cstdint>
#include <string>
#include <thread>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

namespace nimble::foxglove::test {

namespace net = boost::asio;
namespace beast = boost::beast;
namespace http = beast::http;
namespace websocket = beast::websocket;
using tcp = net::ip::tcp;
using nlohmann::json;

/// A WebSocket client of the server, reads bounded in time.
class TestClient {
 public:
  /// Connects and shakes hands offering `subprotocols` (comma-separated, "" for none);
  /// `rcvbuf` > 0 makes the socket's receive buffer that small (a slow client fills up soon).
  beast::error_code connect(uint16_t port, const std::string& subprotocols, int rcvbuf = 0) {
    beast::error_code ec;
    auto& sock = beast::get_lowest_layer(ws_).socket();
    sock.open(tcp::v4(), ec);
    if (rcvbuf > 0) sock.set_option(net::socket_base::receive_buffer_size(rcvbuf), ec);
    sock.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), port), ec);
    if (ec) return ec;
    ws_.set_option(websocket::stream_base::decorator([subprotocols](websocket::request_type& req) {
      if (!subprotocols.empty()) req.set(http::field::sec_websocket_protocol, subprotocols);
    }));
    websocket::response_type res;
    ws_.handshake(res, "127.0.0.1:" + std::to_string(port), "/", ec);
    agreed = std::string(res[http::field::sec_websocket_protocol]);
    return ec;
  }

  /// The next frame within `timeout_s`; false on timeout or error (`error` says which).
  bool read(std::string* frame, bool* text, double timeout_s = 2.0) {
    bool done = false;
    buffer_.clear();
    ws_.async_read(buffer_, [&](beast::error_code ec, std::size_t) {
      error = ec;
      done = true;
    });
    ioc_.restart();
    ioc_.run_for(std::chrono::milliseconds(static_cast<int64_t>(timeout_s * 1000)));
    if (!done) {
      error = net::error::timed_out;
      beast::get_lowest_layer(ws_).cancel();
      ioc_.restart();
      ioc_.run_for(std::chrono::milliseconds(200));
      return false;
    }
    if (error) return false;
    *frame = beast::buffers_to_string(buffer_.data());
    *text = ws_.got_text();
    return true;
  }

  /// The next text frame as JSON (fails the test if there is none, or a binary one).
  json read_json(double timeout_s = 2.0) {
    std::string f;
    bool text = false;
    REQUIRE(read(&f, &text, timeout_s));
    REQUIRE(text);
    return json::parse(f);
  }

  void send_text(const std::string& s) {
    ws_.text(true);
    ws_.write(net::buffer(s));
  }
  void send_binary(const std::string& s) {
    ws_.binary(true);
    ws_.write(net::buffer(s));
  }
  websocket::close_reason reason() const { return ws_.reason(); }

  std::string agreed;
  beast::error_code error;

 private:
  net::io_context ioc_;
  websocket::stream<beast::tcp_stream> ws_{ioc_};
  beast::flat_buffer buffer_;
};

/// Waits until `done()` or `timeout_s` passes.
template <typename F>
inline bool eventually(F done, double timeout_s = 2.0) {
  const auto end = std::chrono::steady_clock::now() + std::chrono::duration<double>(timeout_s);
  while (!done()) {
    if (std::chrono::steady_clock::now() > end) return false;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return true;
}

/// The subscription id, timestamp and payload of a messageData frame (false if it is not one).
inline bool parse_message_data(const std::string& frame, uint32_t* sub, uint64_t* ts, std::string* payload) {
  if (frame.size() < 13 || frame[0] != 0x01) return false;
  *sub = 0;
  *ts = 0;
  for (int i = 3; i >= 0; --i) *sub = (*sub << 8) | static_cast<unsigned char>(frame[1 + i]);
  for (int i = 7; i >= 0; --i) *ts = (*ts << 8) | static_cast<unsigned char>(frame[5 + i]);
  *payload = frame.substr(13);
  return true;
}

}  // namespace nimble::foxglove::test
