#include "foxglove/protocol.h"

#include <limits>
#include <utility>

#include <nlohmann/json.hpp>

namespace nimble::foxglove {
namespace {

using nlohmann::json;

/// JSON text of `j`; strings that are not UTF-8 (a client's bytes echoed back) are repaired.
std::string dump(const json& j) { return j.dump(-1, ' ', false, json::error_handler_t::replace); }

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t')) s.remove_suffix(1);
  return s;
}

/// `j` as a u32 if it is a whole number in range.
bool as_u32(const json& j, uint32_t* out) {
  if (j.is_number_unsigned()) {
    const auto v = j.get<uint64_t>();
    if (v > std::numeric_limits<uint32_t>::max()) return false;
    *out = static_cast<uint32_t>(v);
    return true;
  }
  if (j.is_number_integer()) {
    const auto v = j.get<int64_t>();
    if (v < 0 || v > static_cast<int64_t>(std::numeric_limits<uint32_t>::max())) return false;
    *out = static_cast<uint32_t>(v);
    return true;
  }
  return false;
}

/// A client text shortened for a status message.
std::string excerpt(std::string_view text) {
  constexpr std::size_t kMax = 60;
  return text.size() <= kMax ? std::string(text) : std::string(text.substr(0, kMax)) + "...";
}

/// The client operations of the protocol that a read-only server does not serve.
bool refused_op(const std::string& op) {
  static const char* const kOps[] = {"advertise",
                                     "unadvertise",
                                     "getParameters",
                                     "setParameters",
                                     "subscribeParameterUpdates",
                                     "unsubscribeParameterUpdates",
                                     "subscribeConnectionGraph",
                                     "unsubscribeConnectionGraph",
                                     "fetchAsset"};
  for (const char* k : kOps) {
    if (op == k) return true;
  }
  return false;
}

}  // namespace

std::string choose_subprotocol(std::string_view offered) {
  while (!offered.empty()) {
    const std::size_t comma = offered.find(',');
    const std::string_view one = trim(offered.substr(0, comma));
    if (one == kSubprotocolV1 || one == kSubprotocolSdk) return std::string(one);
    if (comma == std::string_view::npos) break;
    offered.remove_prefix(comma + 1);
  }
  return "";
}

std::string server_info_json(const std::string& name, const std::string& session_id,
                             const std::map<std::string, std::string>& metadata) {
  json j;
  j["op"] = "serverInfo";
  j["name"] = name;
  j["capabilities"] = json::array();
  j["supportedEncodings"] = json::array();
  j["metadata"] = json::object();
  for (const auto& kv : metadata) j["metadata"][kv.first] = kv.second;
  j["sessionId"] = session_id;
  return dump(j);
}

std::string advertise_json(const std::vector<Channel>& channels) {
  json list = json::array();
  for (const auto& c : channels) {
    list.push_back({{"id", c.id},
                    {"topic", c.topic},
                    {"encoding", "json"},
                    {"schemaName", c.schema_name},
                    {"schema", c.schema},
                    {"schemaEncoding", "jsonschema"}});
  }
  return dump(json{{"op", "advertise"}, {"channels", std::move(list)}});
}

std::string unadvertise_json(const std::vector<uint32_t>& channel_ids) {
  return dump(json{{"op", "unadvertise"}, {"channelIds", channel_ids}});
}

std::string status_json(StatusLevel level, const std::string& message) {
  return dump(json{{"op", "status"}, {"level", static_cast<int>(level)}, {"message", message}});
}

void write_message_data_header(uint32_t subscription_id, uint64_t timestamp_ns, unsigned char* out) {
  out[0] = 0x01;
  for (int i = 0; i < 4; ++i) out[1 + i] = static_cast<unsigned char>(subscription_id >> (8 * i));
  for (int i = 0; i < 8; ++i) out[5 + i] = static_cast<unsigned char>(timestamp_ns >> (8 * i));
}

std::string message_data(uint32_t subscription_id, uint64_t timestamp_ns, std::string_view payload) {
  std::string frame(kMessageDataHeader + payload.size(), '\0');
  write_message_data_header(subscription_id, timestamp_ns, reinterpret_cast<unsigned char*>(frame.data()));
  frame.replace(kMessageDataHeader, payload.size(), payload.data(), payload.size());
  return frame;
}

ClientSession::ClientSession(std::function<bool(uint32_t)> channel_exists)
    : channel_exists_(std::move(channel_exists)) {}

bool ClientSession::subscription_of(uint32_t channel_id, uint32_t* subscription_id) const {
  const auto it = by_channel_.find(channel_id);
  if (it == by_channel_.end()) return false;
  *subscription_id = it->second;
  return true;
}

void ClientSession::protocol_error(const std::string& message, std::vector<std::string>* replies) {
  ++counters_.protocol_errors;
  replies->push_back(status_json(StatusLevel::kError, message));
}

void ClientSession::refuse(const std::string& message, std::vector<std::string>* replies) {
  ++counters_.refused;
  replies->push_back(status_json(StatusLevel::kError, message));
}

std::vector<uint32_t> ClientSession::on_text(std::string_view frame, std::vector<std::string>* replies) {
  std::vector<uint32_t> changed;
  const json request = json::parse(frame.begin(), frame.end(), nullptr, /*allow_exceptions=*/false);
  if (request.is_discarded()) {
    protocol_error("not JSON: '" + excerpt(frame) + "'", replies);
    return changed;
  }
  if (!request.is_object()) {
    protocol_error("a client message must be a JSON object with an \"op\"", replies);
    return changed;
  }
  const auto op_it = request.find("op");
  if (op_it == request.end() || !op_it->is_string()) {
    protocol_error("a client message must have a string \"op\"", replies);
    return changed;
  }
  const std::string& op = op_it->get_ref<const std::string&>();
  if (op == "subscribe") {
    subscribe(request, &changed, replies);
  } else if (op == "unsubscribe") {
    unsubscribe(request, &changed, replies);
  } else if (refused_op(op)) {
    refuse("refused '" + op + "': this server is read-only (capabilities: none)", replies);
  } else {
    protocol_error("unknown op '" + excerpt(op) + "'", replies);
  }
  return changed;
}

void ClientSession::on_binary(std::string_view frame, std::vector<std::string>* replies) {
  const int opcode = frame.empty() ? -1 : static_cast<unsigned char>(frame[0]);
  refuse("refused a binary client message (opcode " + std::to_string(opcode) +
             "): this server is read-only (no client publishing, no services)",
         replies);
}

void ClientSession::subscribe(const json& request, std::vector<uint32_t>* changed, std::vector<std::string>* replies) {
  const auto list = request.find("subscriptions");
  if (list == request.end() || !list->is_array()) {
    protocol_error("subscribe: \"subscriptions\" must be an array of {id, channelId}", replies);
    return;
  }
  for (const json& s : *list) {
    uint32_t id = 0, channel = 0;
    if (!s.is_object() || !s.contains("id") || !s.contains("channelId") || !as_u32(s["id"], &id) ||
        !as_u32(s["channelId"], &channel)) {
      protocol_error("subscribe: each subscription must be {id, channelId} with whole numbers in [0, 2^32)", replies);
      continue;
    }
    if (!channel_exists_(channel)) {
      protocol_error("subscribe: no channel " + std::to_string(channel) + " (subscription " + std::to_string(id) + ")",
                     replies);
      continue;
    }
    if (by_subscription_.count(id) != 0) {
      protocol_error("subscribe: subscription id " + std::to_string(id) + " is already in use (channel " +
                         std::to_string(by_subscription_[id]) + ")",
                     replies);
      continue;
    }
    if (by_channel_.count(channel) != 0) {
      protocol_error("subscribe: channel " + std::to_string(channel) + " is already subscribed (subscription " +
                         std::to_string(by_channel_[channel]) + ")",
                     replies);
      continue;
    }
    by_subscription_[id] = channel;
    by_channel_[channel] = id;
    changed->push_back(channel);
  }
}

void ClientSession::unsubscribe(const json& request, std::vector<uint32_t>* changed,
                                std::vector<std::string>* replies) {
  const auto list = request.find("subscriptionIds");
  if (list == request.end() || !list->is_array()) {
    protocol_error("unsubscribe: \"subscriptionIds\" must be an array of numbers", replies);
    return;
  }
  for (const json& s : *list) {
    uint32_t id = 0;
    if (!as_u32(s, &id)) {
      protocol_error("unsubscribe: a subscription id must be a whole number in [0, 2^32)", replies);
      continue;
    }
    const auto it = by_subscription_.find(id);
    if (it == by_subscription_.end()) {
      protocol_error("unsubscribe: no subscription " + std::to_string(id), replies);
      continue;
    }
    changed->push_back(it->second);
    by_channel_.erase(it->second);
    by_subscription_.erase(it);
  }
}

}  // namespace nimble::foxglove
