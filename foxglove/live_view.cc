#include "foxglove/live_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>

#include "contract/channels.h"
#include "contract/message_bounds.h"
#include "lcmjson/lcm_json.h"

namespace nimble::foxglove {
namespace {

int64_t now_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(std::chrono::steady_clock::now().time_since_epoch())
      .count();
}

constexpr int64_t kStateRepeatNs = 1000000000LL;

const char* const kVerdictSchema =
    R"({"$schema":"https://json-schema.org/draft/2020-12/schema",)"
    R"("title":"nimble.run_verdict","type":"object",)"
    R"("description":"The run's state and verdict, as the launcher or the replay sees it.",)"
    R"("properties":{)"
    R"("state":{"type":"string","description":"running, done, replaying, ..."},)"
    R"("verdict":{"type":"string","description":"the verdict's text; empty until the end"},)"
    R"("t_s":{"type":"number","description":"simulated time reached","x-unit":"s"},)"
    R"("beyond_bounds":{"type":"string","description":"messages left out with a value beyond the vehicle's )"
    R"(physical bounds: channel, field, time and count; absent when there are none"}},)"
    R"("required":["state","verdict","t_s"]})";

/// Whether the rig time of `type` sits at a fixed offset (only fixed-size scalars before it),
/// so that reading it costs nothing.
bool rig_time_is_cheap(const lcmjson::LcmStruct& type) {
  if (type.rig_time_field < 0) return false;
  for (int i = 0; i < type.rig_time_field; ++i) {
    const lcmjson::LcmField& f = type.fields[static_cast<std::size_t>(i)];
    if (!f.dims.empty() || f.type == "string") return false;
  }
  return true;
}

}  // namespace

LiveView::LiveView(FoxgloveServer& server, LiveViewOptions options) : server_(server), options_(options) {
  for (const contract::ChannelSpec& spec : contract::channel_table()) {
    const lcmjson::LcmStruct* type = lcmjson::rig_type_for_channel(spec.name);
    if (type == nullptr) continue;  // lcmjson's test keeps the contract and the types in step
    routes_[spec.name] = Route{server_.add_channel(spec.name, type->full_name(), lcmjson::json_schema(*type)), type,
                               contract::due_in_sim_time(spec.name) && rig_time_is_cheap(*type), spec.name,
                               options_.vehicle.has_value() && contract::type_has_bounds(spec.type)};
  }
  if (options_.vehicle) beyond_.emplace(*options_.vehicle);
  verdict_id_ = server_.add_channel(kVerdictTopic, kVerdictSchemaName, kVerdictSchema);
  for (const auto& kv : routes_) by_id_[kv.second.id] = &kv.second;
  if (has_history()) {
    server_.set_subscribe_handler([this](const FoxgloveServer::NewSubscription& s) { on_subscribe(s); });
  }
}

void LiveView::start() {
  std::lock_guard<std::mutex> lock(mu_);
  if (started_ || stopping_) return;
  started_ = true;
  thread_ = std::thread([this] {
    set_thread_nice(options_.thread_nice);
    run();
  });
}

LiveView::~LiveView() {
  stop();
  if (has_history()) server_.set_subscribe_handler(nullptr);
}

uint32_t LiveView::channel_id(const std::string& topic) const {
  if (topic == kVerdictTopic) return verdict_id_;
  const auto it = routes_.find(topic);
  return it == routes_.end() ? 0 : it->second.id;
}

void LiveView::offer(const std::string& channel, const void* data, std::size_t size, bool wait_for_room) {
  const auto it = routes_.find(channel);
  if (it == routes_.end()) return;
  const Route& route = it->second;
  // The newest rig time, for the messages that carry none (and rig/verdict).
  int64_t stamp = -1;
  if (route.tracks_rig_time) stamp = lcmjson::rig_time_us(*route.type, data, size);
  const bool wanted = server_.has_subscribers(route.id);
  if (!has_history() && !wanted) {
    if (stamp > newest_rig_us_.load(std::memory_order_relaxed)) newest_rig_us_.store(stamp, std::memory_order_relaxed);
    return;
  }
  std::unique_lock<std::mutex> lock(mu_);
  const auto full = [&] {
    return queue_bytes_ + size > options_.max_queue_bytes || queue_.size() + 1 > options_.max_queue_messages;
  };
  if (wait_for_room && started_ && full()) room_cv_.wait(lock, [&] { return stopping_ || !full(); });
  // Under the lock, so that the stamps follow the queue's order (several threads may offer).
  int64_t newest = newest_rig_us_.load(std::memory_order_relaxed);
  if (stamp > newest) newest_rig_us_.store(newest = stamp, std::memory_order_relaxed);
  if (stamp < 0) stamp = newest;
  if (stopping_) return;
  if (wanted) ++stats_.offered;
  if (full()) {
    ++(wanted ? stats_.dropped : stats_.history_dropped);
    return;
  }
  Pending p;
  p.route = &route;
  p.bytes.assign(static_cast<const char*>(data), size);
  p.stamp_us = stamp;
  queue_.push_back(std::move(p));
  queue_bytes_ += size;
  if (queue_.size() == 1) cv_.notify_one();
}

void LiveView::on_subscribe(const FoxgloveServer::NewSubscription& s) {
  {
    std::lock_guard<std::mutex> lock(mu_);
    if (!stopping_) {
      // Behind every message offered so far: the thread answers it after keeping them.
      Pending p;
      p.subscription = s;
      queue_.push_back(std::move(p));
      if (queue_.size() == 1) cv_.notify_one();
      return;
    }
  }
  server_.deliver_backlog(s, {});  // stopped: nothing more is published, nothing to wait for
}

void LiveView::restart() {
  std::lock_guard<std::mutex> lock(mu_);
  newest_rig_us_.store(-1, std::memory_order_relaxed);
  if (stopping_ || !has_history()) return;
  Pending p;
  p.restart = true;
  queue_.push_back(std::move(p));
  if (queue_.size() == 1) cv_.notify_one();
}

void LiveView::keep(const Route& route, int64_t stamp_us, std::string bytes) {
  History& h = history_[route.id];
  h.bytes += bytes.size() + sizeof(Kept);
  h.kept.push_back(Kept{stamp_us, std::move(bytes)});
  const int64_t newest = newest_rig_us_.load(std::memory_order_relaxed);
  const auto window_us = static_cast<int64_t>(options_.history_s * 1e6);
  while (!h.kept.empty() &&
         (h.bytes > options_.history_bytes || (newest >= 0 && h.kept.front().stamp_us < newest - window_us))) {
    h.bytes -= h.kept.front().bytes.size() + sizeof(Kept);
    h.kept.pop_front();
  }
}

void LiveView::answer(const FoxgloveServer::NewSubscription& s, lcmjson::JsonMessage* message) {
  if (s.channel == verdict_id_) {
    // The newest state, under the lock that set_state() publishes under: nothing in between.
    std::lock_guard<std::mutex> lock(mu_);
    std::vector<FoxgloveServer::BacklogMessage> state;
    if (has_state_) {
      const int64_t rig_us = newest_rig_us_.load(std::memory_order_relaxed);
      state.push_back({static_cast<uint64_t>(rig_us > 0 ? rig_us * 1000 : 0), state_json_locked()});
    }
    server_.deliver_backlog(s, state);
    return;
  }
  std::vector<FoxgloveServer::BacklogMessage> backlog;
  const auto it = history_.find(s.channel);
  if (it != history_.end() && server_.holds(s)) {
    // The window of the newest rig time now (a channel that fell silent keeps no older messages).
    const int64_t newest = newest_rig_us_.load(std::memory_order_relaxed);
    const auto window_us = static_cast<int64_t>(options_.history_s * 1e6);
    const Route& route = *by_id_.at(s.channel);
    backlog.reserve(it->second.kept.size());
    for (const Kept& k : it->second.kept) {
      if (newest >= 0 && k.stamp_us < newest - window_us) continue;
      if (!lcmjson::to_json(*route.type, k.bytes.data(), k.bytes.size(), message).empty()) continue;
      const int64_t t_us = message->rig_time_us >= 0 ? message->rig_time_us : std::max<int64_t>(k.stamp_us, 0);
      backlog.push_back({static_cast<uint64_t>(t_us) * 1000u, std::move(message->json)});
    }
  }
  if (server_.deliver_backlog(s, backlog)) {
    std::lock_guard<std::mutex> lock(mu_);
    ++stats_.backlogs;
    stats_.backlog_messages += static_cast<int64_t>(backlog.size());
  }
}

void LiveView::set_state(const std::string& state, const std::string& verdict, double t_s) {
  std::lock_guard<std::mutex> lock(mu_);
  state_ = state;
  verdict_ = verdict;
  state_t_s_ = std::isfinite(t_s) ? t_s : 0.0;
  has_state_ = true;
  publish_state_locked(now_ns());
}

std::string LiveView::state_json_locked() const {
  const int64_t rig_us = newest_rig_us_.load(std::memory_order_relaxed);
  const bool live = state_ == "running" || state_ == "replaying";
  const double t_s = live && rig_us > 0 ? std::max(state_t_s_, static_cast<double>(rig_us) / 1e6) : state_t_s_;
  nlohmann::json j{{"state", state_}, {"verdict", verdict_}, {"t_s", t_s}};
  if (stats_.beyond_bounds > 0) j["beyond_bounds"] = stats_.beyond_bounds_text;
  return j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace);
}

void LiveView::publish_state_locked(int64_t now) {
  if (!has_state_) return;
  const int64_t rig_us = newest_rig_us_.load(std::memory_order_relaxed);
  server_.publish(verdict_id_, static_cast<uint64_t>(rig_us > 0 ? rig_us * 1000 : 0), state_json_locked());
  state_sent_ns_ = now;
}

bool LiveView::beyond_bounds(const Route& route, int64_t stamp_us, const std::string& bytes) {
  if (!route.bounded) return false;
  const uint64_t before = beyond_->messages();
  const int64_t t_us = route.tracks_rig_time ? stamp_us : lcmjson::rig_time_us(*route.type, bytes.data(), bytes.size());
  contract::check_message_bounds(route.channel, bytes.data(), static_cast<int>(bytes.size()),
                                 static_cast<double>(t_us) * 1e-6, *beyond_);
  if (beyond_->messages() == before) return false;
  std::lock_guard<std::mutex> lock(mu_);
  stats_.beyond_bounds = static_cast<int64_t>(beyond_->messages());
  stats_.beyond_bounds_text = beyond_->text();
  return true;
}

void LiveView::run() {
  lcmjson::JsonMessage message;
  std::deque<Pending> batch;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mu_);
      busy_ = false;
      idle_cv_.notify_all();
      cv_.wait_for(lock, std::chrono::milliseconds(250), [this] { return stopping_ || !queue_.empty(); });
      const int64_t now = now_ns();
      if (now - state_sent_ns_ >= kStateRepeatNs) publish_state_locked(now);
      if (queue_.empty() && stopping_) return;
      batch.swap(queue_);
      queue_bytes_ = 0;
      busy_ = !batch.empty();
    }
    room_cv_.notify_all();
    int64_t undecodable = 0, published = 0;
    for (Pending& p : batch) {
      if (p.route == nullptr) {
        if (p.restart)
          history_.clear();
        else
          answer(p.subscription, &message);
        continue;
      }
      // Garbage that decoded: not plotted as a number (not sent), not kept for late clients.
      if (beyond_bounds(*p.route, p.stamp_us, p.bytes)) continue;
      if (server_.has_subscribers(p.route->id)) {
        const std::string why = lcmjson::to_json(*p.route->type, p.bytes.data(), p.bytes.size(), &message);
        if (why.empty()) {
          const int64_t own = message.rig_time_us;
          const int64_t t_us = own >= 0 ? own : std::max<int64_t>(p.stamp_us, 0);
          server_.publish(p.route->id, static_cast<uint64_t>(t_us) * 1000u, message.json);
          ++published;
        } else {
          ++undecodable;
        }
      }
      // Kept whether decodable or not: a late client's backlog leaves out what does not decode.
      if (has_history()) keep(*p.route, p.stamp_us, std::move(p.bytes));
    }
    batch.clear();
    std::lock_guard<std::mutex> lock(mu_);
    stats_.undecodable += undecodable;
    stats_.published += published;
  }
}

bool LiveView::flush(double timeout_s) {
  std::unique_lock<std::mutex> lock(mu_);
  if (!started_) return queue_.empty();
  return idle_cv_.wait_for(lock, std::chrono::duration<double>(timeout_s), [this] { return queue_.empty() && !busy_; });
}

void LiveView::stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
  room_cv_.notify_all();
  if (thread_.joinable()) thread_.join();
}

LiveViewStats LiveView::stats() const {
  LiveViewStats s;
  {
    std::lock_guard<std::mutex> lock(mu_);
    s = stats_;
  }
  s.server = server_.stats();
  return s;
}

}  // namespace nimble::foxglove
