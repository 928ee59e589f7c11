/// The socket-free part of the Foxglove server: one client's session, the messages it sends.

#include <catch2/catch.hpp>

#include <nlohmann/json.hpp>

#include "foxglove/protocol.h"
#include "contract/channels.h"

// Channel names come from the contract (functional.contract checks that no file spells them).
using nimble::contract::channels::kTruth;

using namespace nimble::foxglove;
using nlohmann::json;

namespace {

/// A session on a server with channels 1..3.
ClientSession session() {
  return ClientSession([](uint32_t id) { return id >= 1 && id <= 3; });
}

json only_reply(const std::vector<std::string>& replies) {
  REQUIRE(replies.size() == 1);
  return json::parse(replies[0]);
}

}  // namespace

TEST_CASE("subprotocol: the first the client offers that the server speaks", "[foxglove][protocol]") {
  CHECK(choose_subprotocol("foxglove.websocket.v1") == "foxglove.websocket.v1");
  CHECK(choose_subprotocol("foxglove.sdk.v1") == "foxglove.sdk.v1");
  CHECK(choose_subprotocol("other, foxglove.sdk.v1 ,foxglove.websocket.v1") == "foxglove.sdk.v1");
  CHECK(choose_subprotocol("").empty());
  CHECK(choose_subprotocol("chat, superchat").empty());
  CHECK(choose_subprotocol("foxglove.websocket.v2").empty());
}

TEST_CASE("server messages: serverInfo, advertise, status, messageData", "[foxglove][protocol]") {
  const json info = json::parse(server_info_json("rig", "s1", {{"scenario", "hover"}}));
  CHECK(info["op"] == "serverInfo");
  CHECK(info["name"] == "rig");
  CHECK(info["capabilities"] == json::array());
  CHECK(info["sessionId"] == "s1");
  CHECK(info["metadata"]["scenario"] == "hover");

  const json ad = json::parse(advertise_json({Channel{7, kTruth, "nimble.truth_state_t", "{\"type\":\"object\"}"}}));
  CHECK(ad["op"] == "advertise");
  REQUIRE(ad["channels"].size() == 1);
  const json& c = ad["channels"][0];
  CHECK(c["id"] == 7);
  CHECK(c["topic"] == kTruth);
  CHECK(c["encoding"] == "json");
  CHECK(c["schemaName"] == "nimble.truth_state_t");
  CHECK(c["schemaEncoding"] == "jsonschema");
  CHECK(c["schema"] == "{\"type\":\"object\"}");

  CHECK(json::parse(unadvertise_json({1, 2}))["channelIds"] == json::array({1, 2}));
  const json st = json::parse(status_json(StatusLevel::kWarning, "bad \xff byte"));
  CHECK(st["op"] == "status");
  CHECK(st["level"] == 1);

  const std::string frame = message_data(0x01020304u, 0x1122334455667788ull, "{}");
  REQUIRE(frame.size() == kMessageDataHeader + 2);
  const unsigned char expected[] = {0x01, 0x04, 0x03, 0x02, 0x01, 0x88, 0x77, 0x66, 0x55, 0x44, 0x33, 0x22, 0x11};
  for (std::size_t i = 0; i < kMessageDataHeader; ++i) CHECK(static_cast<unsigned char>(frame[i]) == expected[i]);
  CHECK(frame.substr(kMessageDataHeader) == "{}");
}

TEST_CASE("session: subscribe and unsubscribe", "[foxglove][protocol]") {
  ClientSession s = session();
  std::vector<std::string> replies;
  auto changed =
      s.on_text(R"({"op":"subscribe","subscriptions":[{"id":10,"channelId":1},{"id":11,"channelId":3}]})", &replies);
  CHECK(replies.empty());
  CHECK(changed == std::vector<uint32_t>{1, 3});
  uint32_t sub = 0;
  REQUIRE(s.subscription_of(3, &sub));
  CHECK(sub == 11);
  CHECK_FALSE(s.subscription_of(2, &sub));

  changed = s.on_text(R"({"op":"unsubscribe","subscriptionIds":[10]})", &replies);
  CHECK(replies.empty());
  CHECK(changed == std::vector<uint32_t>{1});
  CHECK_FALSE(s.subscription_of(1, &sub));
  CHECK(s.subscriptions().size() == 1);
  // An id may be reused once unsubscribed.
  changed = s.on_text(R"({"op":"subscribe","subscriptions":[{"id":10,"channelId":2}]})", &replies);
  CHECK(replies.empty());
  CHECK(changed == std::vector<uint32_t>{2});
  CHECK(s.counters().protocol_errors == 0);
  CHECK(s.counters().refused == 0);
}

TEST_CASE("session: each bad request is a status error, counted, and changes nothing", "[foxglove][protocol]") {
  struct Case {
    const char* name;
    std::string text;
    const char* says;
  };
  const std::vector<Case> cases = {
      {"garbage", "hello", "not JSON"},
      {"invalid JSON", R"({"op":"subscribe",)", "not JSON"},
      {"not an object", "[1,2]", "JSON object"},
      {"no op", R"({"subscriptions":[]})", "\"op\""},
      {"op not a string", R"({"op":5})", "\"op\""},
      {"unknown op", R"({"op":"explode"})", "unknown op 'explode'"},
      {"subscriptions missing", R"({"op":"subscribe"})", "must be an array"},
      {"subscription not an object", R"({"op":"subscribe","subscriptions":[3]})", "{id, channelId}"},
      {"negative id", R"({"op":"subscribe","subscriptions":[{"id":-1,"channelId":1}]})", "{id, channelId}"},
      {"id beyond u32", R"({"op":"subscribe","subscriptions":[{"id":4294967296,"channelId":1}]})", "{id, channelId}"},
      {"fractional id", R"({"op":"subscribe","subscriptions":[{"id":1.5,"channelId":1}]})", "{id, channelId}"},
      {"unknown channel", R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":99}]})", "no channel 99"},
      {"unsubscribe unknown", R"({"op":"unsubscribe","subscriptionIds":[42]})", "no subscription 42"},
      {"unsubscribe not numbers", R"({"op":"unsubscribe","subscriptionIds":["a"]})", "whole number"},
      {"unsubscribe no list", R"({"op":"unsubscribe"})", "must be an array"},
  };
  for (const auto& c : cases) {
    INFO(c.name);
    ClientSession s = session();
    std::vector<std::string> replies;
    const auto changed = s.on_text(c.text, &replies);
    CHECK(changed.empty());
    const json r = only_reply(replies);
    CHECK(r["op"] == "status");
    CHECK(r["level"] == 2);
    CHECK_THAT(r["message"].get<std::string>(), Catch::Contains(c.says));
    CHECK(s.counters().protocol_errors == 1);
    CHECK(s.counters().refused == 0);
    CHECK(s.subscriptions().empty());
  }
}

TEST_CASE("session: duplicate subscription id and a second subscription of a channel are refused",
          "[foxglove][protocol]") {
  ClientSession s = session();
  std::vector<std::string> replies;
  s.on_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":1}]})", &replies);
  REQUIRE(replies.empty());
  auto changed = s.on_text(R"({"op":"subscribe","subscriptions":[{"id":1,"channelId":2},{"id":2,"channelId":1},)"
                           R"({"id":3,"channelId":3}]})",
                           &replies);
  // The good one of the three is taken.
  CHECK(changed == std::vector<uint32_t>{3});
  REQUIRE(replies.size() == 2);
  CHECK_THAT(json::parse(replies[0])["message"].get<std::string>(), Catch::Contains("already in use"));
  CHECK_THAT(json::parse(replies[1])["message"].get<std::string>(), Catch::Contains("already subscribed"));
  CHECK(s.counters().protocol_errors == 2);
  uint32_t sub = 0;
  REQUIRE(s.subscription_of(1, &sub));
  CHECK(sub == 1);
}

TEST_CASE("session: read-only: client publishing, parameters, services and binary frames are refused",
          "[foxglove][protocol]") {
  ClientSession s = session();
  std::vector<std::string> replies;
  const char* const refused[] = {
      R"({"op":"advertise","channels":[{"id":1,"topic":"x","encoding":"json","schemaName":"x"}]})",
      R"({"op":"unadvertise","channelIds":[1]})",
      R"({"op":"getParameters","parameterNames":[]})",
      R"({"op":"setParameters","parameters":[{"name":"a","value":1}]})",
      R"({"op":"subscribeParameterUpdates","parameterNames":[]})",
      R"({"op":"unsubscribeParameterUpdates","parameterNames":[]})",
      R"({"op":"subscribeConnectionGraph"})",
      R"({"op":"unsubscribeConnectionGraph"})",
      R"({"op":"fetchAsset","uri":"package://x","requestId":1})",
  };
  for (const char* r : refused) s.on_text(r, &replies);
  s.on_binary(std::string("\x01\x00\x00\x00\x00{}", 7), &replies);
  s.on_binary("", &replies);
  REQUIRE(replies.size() == 11);
  for (const auto& r : replies) {
    const json j = json::parse(r);
    CHECK(j["level"] == 2);
    CHECK_THAT(j["message"].get<std::string>(), Catch::Contains("read-only"));
  }
  CHECK(s.counters().refused == 11);
  CHECK(s.counters().protocol_errors == 0);
}

TEST_CASE("session: arbitrary bytes never crash it and every reply is JSON", "[foxglove][protocol]") {
  ClientSession s = session();
  uint32_t state = 12345;
  for (int n = 0; n < 2000; ++n) {
    std::string text;
    const int len = static_cast<int>(state % 64);
    for (int i = 0; i < len; ++i) {
      state = state * 1103515245u + 12345u;
      const char alphabet[] = "{}[]\":,0123456789-.eE opsubcrieidtnlI\\\xff\x00";
      text += alphabet[(state >> 16) % (sizeof alphabet - 1)];
    }
    std::vector<std::string> replies;
    s.on_text(text, &replies);
    for (const auto& r : replies) CHECK_FALSE(json::parse(r, nullptr, false).is_discarded());
  }
  std::vector<std::string> replies;
  s.on_text(std::string(100000, '['), &replies);
  CHECK(replies.size() == 1);
}
