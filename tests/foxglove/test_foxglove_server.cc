/// The Foxglove WebSocket server with a Boost.Beast WebSocket client in this process: the
/// handshake, what a client is sent, subscriptions, refusals, bounds, and a publisher that a
/// client which does not read never holds up.

#include <catch2/catch.hpp>

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <boost/asio/connect.hpp>
#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/http.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>

#include "foxglove/foxglove_server.h"
#include "tests/foxglove/ws_test_client.h"
#include "tests/support/scratch.h"

using namespace nimble::foxglove;
using namespace nimble::foxglove::test;

namespace {

ServerOptions any_port() {
  ServerOptions o;
  o.port = 0;
  o.name = "test server";
  return o;
}

/// A server on a free port with channels A (1) and B (2), started.
struct Fixture {
  Fixture() : Fixture(any_port()) {}
  explicit Fixture(ServerOptions o) : server(std::move(o)) {
    a = server.add_channel("A", "test.a", R"({"type":"object"})");
    b = server.add_channel("B", "test.b", R"({"type":"object","properties":{"x":{"type":"number"}}})");
    server.start();
  }
  FoxgloveServer server;
  uint32_t a = 0, b = 0;
};

/// Connects, reads serverInfo and advertise.
void join(TestClient& c, Fixture& f, const std::string& sub = kSubprotocolV1) {
  REQUIRE_FALSE(c.connect(f.server.port(), sub));
  CHECK(c.read_json()["op"] == "serverInfo");
  CHECK(c.read_json()["op"] == "advertise");
}

}  // namespace

TEST_CASE("server: binds a free port with port 0 and names it", "[foxglove][server]") {
  FoxgloveServer s(any_port());
  CHECK(s.port() != 0);
  CHECK(s.url() == "ws://127.0.0.1:" + std::to_string(s.port()));
  // The same port again is an error naming it.
  ServerOptions o = any_port();
  o.port = s.port();
  CHECK_THROWS_WITH(FoxgloveServer(o), Catch::Contains("cannot listen on 127.0.0.1:" + std::to_string(s.port())));
  o.host = "not-an-address";
  CHECK_THROWS_WITH(FoxgloveServer(o), Catch::Contains("not an IP address"));
}

TEST_CASE("server: [HOST:]PORT", "[foxglove][server]") {
  std::string host;
  uint16_t port = 0;
  parse_host_port("9000", "127.0.0.1", &host, &port);
  CHECK((host == "127.0.0.1" && port == 9000));
  parse_host_port("0.0.0.0:0", "127.0.0.1", &host, &port);
  CHECK((host == "0.0.0.0" && port == 0));
  parse_host_port("[::1]:8765", "127.0.0.1", &host, &port);
  CHECK((host == "::1" && port == 8765));
  CHECK_THROWS_WITH(parse_host_port("70000", "h", &host, &port), Catch::Contains("0 to 65535"));
  CHECK_THROWS_WITH(parse_host_port("host:", "h", &host, &port), Catch::Contains("0 to 65535"));
  CHECK_THROWS_WITH(parse_host_port(":80", "h", &host, &port), Catch::Contains("empty host"));
  CHECK_THROWS_WITH(parse_host_port("::1:80", "h", &host, &port), Catch::Contains("brackets"));
}

TEST_CASE("server: handshake with each subprotocol, serverInfo then advertise", "[foxglove][server]") {
  Fixture f;
  for (const std::string& sub : {std::string(kSubprotocolV1), std::string(kSubprotocolSdk)}) {
    INFO(sub);
    TestClient c;
    REQUIRE_FALSE(c.connect(f.server.port(), "something.else, " + sub));
    CHECK(c.agreed == sub);
    const json info = c.read_json();
    CHECK(info["op"] == "serverInfo");
    CHECK(info["name"] == "test server");
    CHECK(info["capabilities"] == json::array());
    const json ad = c.read_json();
    CHECK(ad["op"] == "advertise");
    REQUIRE(ad["channels"].size() == 2);
    CHECK(ad["channels"][0]["id"] == f.a);
    CHECK(ad["channels"][0]["topic"] == "A");
    CHECK(ad["channels"][1]["schemaName"] == "test.b");
    CHECK(ad["channels"][1]["encoding"] == "json");
    CHECK(ad["channels"][1]["schemaEncoding"] == "jsonschema");
    CHECK(json::parse(ad["channels"][1]["schema"].get<std::string>())["properties"]["x"]["type"] == "number");
  }
  CHECK(eventually([&] { return f.server.stats().clients_total == 2; }));
}

TEST_CASE("server: a handshake without the protocol's subprotocol is refused", "[foxglove][server]") {
  Fixture f;
  for (const std::string& offered : {std::string("chat"), std::string("")}) {
    INFO("offered '" << offered << "'");
    TestClient c;
    const beast::error_code ec = c.connect(f.server.port(), offered);
    CHECK(ec == websocket::error::upgrade_declined);
  }
  CHECK(f.server.stats().handshakes_refused == 2);
  CHECK(f.server.stats().clients_total == 0);
}

TEST_CASE(
    "server: subscribe gives messageData with the subscription id, timestamp and payload, unsubscribe "
    "stops them",
    "[foxglove][server]") {
  Fixture f;
  TestClient c;
  join(c, f);
  CHECK_FALSE(f.server.has_subscribers(f.b));
  c.send_text(R"({"op":"subscribe","subscriptions":[{"id":77,"channelId":2}]})");
  REQUIRE(eventually([&] { return f.server.has_subscribers(f.b); }));
  CHECK_FALSE(f.server.has_subscribers(f.a));
  f.server.publish(f.a, 1, R"({"not":"subscribed"})");
  f.server.publish(f.b, 1234567890123ull, R"({"x":1.5})");
  std::string frame;
  bool text = true;
  REQUIRE(c.read(&frame, &text));
  CHECK_FALSE(text);
  REQUIRE(frame.size() == kMessageDataHeader + 9);
  CHECK(frame[0] == 0x01);
  uint32_t sub = 0;
  uint64_t ts = 0;
  for (int i = 3; i >= 0; --i) sub = (sub << 8) | static_cast<unsigned char>(frame[1 + i]);
  for (int i = 7; i >= 0; --i) ts = (ts << 8) | static_cast<unsigned char>(frame[5 + i]);
  CHECK(sub == 77);
  CHECK(ts == 1234567890123ull);
  CHECK(frame.substr(kMessageDataHeader) == R"({"x":1.5})");
  CHECK(eventually([&] { return f.server.stats().messages_sent == 1; }));

  c.send_text(R"({"op":"unsubscribe","subscriptionIds":[77]})");
  REQUIRE(eventually([&] { return !f.server.has_subscribers(f.b); }));
  f.server.publish(f.b, 2, R"({"x":2})");
  CHECK_FALSE(c.read(&frame, &text, 0.3));
  const auto clients = f.server.clients();
  REQUIRE(clients.size() == 1);
  CHECK(clients[0].messages_sent == 1);
  CHECK(clients[0].subscriptions == 0);
}

TEST_CASE("server: bad client messages get a status error and are counted, the connection stays",
          "[foxglove][server]") {
  Fixture f;
  TestClient c;
  join(c, f);
  c.send_text("garbage");
  CHECK(c.read_json()["level"] == 2);
  c.send_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":42}]})");
  CHECK_THAT(c.read_json()["message"].get<std::string>(), Catch::Contains("no channel 42"));
  c.send_text(R"({"op":"setParameters","parameters":[]})");
  CHECK_THAT(c.read_json()["message"].get<std::string>(), Catch::Contains("read-only"));
  c.send_binary(std::string("\x01\x01\x00\x00\x00{}", 7));
  CHECK_THAT(c.read_json()["message"].get<std::string>(), Catch::Contains("binary"));
  const ServerStats s = f.server.stats();
  CHECK(s.protocol_errors == 2);
  CHECK(s.refused == 2);
  // Still served.
  c.send_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  REQUIRE(eventually([&] { return f.server.has_subscribers(f.a); }));
}

TEST_CASE("server: a frame over the limit closes the connection (1009)", "[foxglove][server]") {
  ServerOptions o = any_port();
  o.max_frame_bytes = 64 * 1024;
  Fixture f(o);
  TestClient c;
  join(c, f);
  c.send_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})");
  REQUIRE(eventually([&] { return f.server.has_subscribers(f.a); }));
  c.send_text(std::string(70 * 1024, ' '));
  std::string frame;
  bool text = false;
  CHECK_FALSE(c.read(&frame, &text));
  // The server closes the TCP connection right after its close frame: the client's answer to it
  // may meet a closed socket, or the socket's end.
  INFO(c.error.message());
  CHECK((c.error == websocket::error::closed || c.error == net::error::broken_pipe ||
         c.error == net::error::connection_reset || c.error == net::error::eof ||
         c.error == net::error::not_connected));
  CHECK(c.reason().code == websocket::close_code::too_big);
  CHECK(eventually([&] { return f.server.stats().clients_now == 0; }));
  CHECK(f.server.stats().oversized_closes == 1);
  CHECK_FALSE(f.server.has_subscribers(f.a));  // its subscriptions went with it
}

TEST_CASE("server: a client that does not read loses messages, counted, and publish() never waits for it",
          "[foxglove][server]") {
  ServerOptions o = any_port();
  o.max_queue_bytes = 256 * 1024;
  o.max_queue_messages = 500;
  Fixture f(o);
  TestClient slow, fast;
  join(slow, f);
  join(fast, f);
  // The slow client's receive buffer is small and it stops reading after subscribing.
  slow.send_text(R"({"op":"subscribe","subscriptions":[{"id":5,"channelId":1}]})");
  REQUIRE(eventually([&] { return f.server.has_subscribers(f.a); }));
  const std::string payload = "{\"pad\":\"" + std::string(1000, 'x') + "\"}";
  constexpr int kMessages = 20000;  // 20 MB: far beyond the socket buffers and the queue
  std::vector<double> took_s(kMessages);
  const auto t0 = std::chrono::steady_clock::now();
  for (int i = 0; i < kMessages; ++i) {
    const auto a = std::chrono::steady_clock::now();
    f.server.publish(f.a, static_cast<uint64_t>(i), payload);
    took_s[static_cast<std::size_t>(i)] = std::chrono::duration<double>(std::chrono::steady_clock::now() - a).count();
  }
  const double total_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::sort(took_s.begin(), took_s.end());
  const double p99_s = took_s[took_s.size() * 99 / 100];
  INFO("total " << total_s << " s, publish() p99 " << p99_s * 1e6 << " us, slowest " << took_s.back() * 1e3 << " ms");
  // A publisher that waited for the client would wait on every call once the socket is full: the
  // p99 and the total show it; the slowest single call may include a preemption of this thread.
  CHECK(total_s < 2.0);
  CHECK(p99_s < 0.001);
  const ServerStats s = f.server.stats();
  CHECK(s.dropped > kMessages / 2);
  CHECK(s.dropped + s.messages_sent <= kMessages);
  const auto clients = f.server.clients();
  REQUIRE(clients.size() == 2);
  int64_t dropped = 0;
  for (const auto& c : clients) dropped += c.dropped;
  CHECK(dropped == s.dropped);
  // The other client, not subscribed, still gets its status replies at once.
  fast.send_text("{}");
  CHECK(fast.read_json()["level"] == 2);
}

TEST_CASE("server: static files over HTTP on the same port", "[foxglove][server]") {
  const std::filesystem::path root = nimble::test::scratch_dir("fox_web");
  std::filesystem::create_directories(root / "js");
  std::ofstream(root / "index.html") << "<html>dashboard</html>";
  std::ofstream(root / "js" / "app.js") << "console.log(1);";
  ServerOptions o = any_port();
  o.web_root = root.string();
  Fixture f(o);
  const auto get = [&](const std::string& target, std::string* type) {
    net::io_context ioc;
    beast::tcp_stream stream(ioc);
    stream.connect(tcp::endpoint(net::ip::make_address("127.0.0.1"), f.server.port()));
    http::request<http::empty_body> req(http::verb::get, target, 11);
    req.set(http::field::host, "127.0.0.1");
    http::write(stream, req);
    beast::flat_buffer buf;
    http::response<http::string_body> res;
    http::read(stream, buf, res);
    *type = std::string(res[http::field::content_type]);
    return std::make_pair(res.result_int(), res.body());
  };
  std::string type;
  auto r = get("/?ws=ws://127.0.0.1:8765", &type);
  CHECK(r.first == 200);
  CHECK(r.second == "<html>dashboard</html>");
  CHECK_THAT(type, Catch::StartsWith("text/html"));
  r = get("/js/app.js", &type);
  CHECK(r.first == 200);
  CHECK_THAT(type, Catch::StartsWith("text/javascript"));
  CHECK(get("/../../etc/passwd", &type).first == 400);
  CHECK(get("/js/%2e%2e/x", &type).first == 400);
  CHECK(get("/missing.css", &type).first == 404);
  // The WebSocket still works on the same port.
  TestClient c;
  join(c, f);
  std::filesystem::remove_all(root);
  CHECK(f.server.stats().http_requests == 5);
}

TEST_CASE("server: stop() closes clients with a close frame", "[foxglove][server]") {
  Fixture f;
  TestClient c;
  join(c, f);
  f.server.stop();  // this client does not read while the server stops: its socket is closed after the frame
  std::string frame;
  bool text = false;
  CHECK_FALSE(c.read(&frame, &text));
  CHECK(c.error != net::error::timed_out);
  CHECK(c.reason().code == websocket::close_code::normal);
}
