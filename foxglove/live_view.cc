#include "foxglove/live_view.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <utility>

#include <nlohmann/json.hpp>

#include "contract/channels.h"
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
    R"("t_s":{"type":"number","description":"simulated time reached","x-unit":"s"}},)"
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
                               contract::due_in_sim_time(spec.name) && rig_time_is_cheap(*type)};
  }
  verdict_id_ = server_.add_channel(kVerdictTopic, kVerdictSchemaName, kVerdictSchema);
}

void LiveView::start() {
  std::lock_guard<std::mutex> lock(mu_);
  if (thread_.joinable() || stopping_) return;
  thread_ = std::thread([this] {
    set_thread_nice(options_.thread_nice);
    run();
  });
}

LiveView::~LiveView() { stop(); }

uint32_t LiveView::channel_id(const std::string& topic) const {
  if (topic == kVerdictTopic) return verdict_id_;
  const auto it = routes_.find(topic);
  return it == routes_.end() ? 0 : it->second.id;
}

void LiveView::offer(const std::string& channel, const void* data, std::size_t size) {
  const auto it = routes_.find(channel);
  if (it == routes_.end()) return;
  const Route& route = it->second;
  // The newest rig time, for the messages that carry none (and rig/verdict).
  if (route.tracks_rig_time) {
    const int64_t t = lcmjson::rig_time_us(*route.type, data, size);
    if (t > newest_rig_us_.load(std::memory_order_relaxed)) newest_rig_us_.store(t, std::memory_order_relaxed);
  }
  if (!server_.has_subscribers(route.id)) return;
  std::lock_guard<std::mutex> lock(mu_);
  if (stopping_) return;
  ++stats_.offered;
  if (queue_bytes_ + size > options_.max_queue_bytes || queue_.size() + 1 > options_.max_queue_messages) {
    ++stats_.dropped;
    return;
  }
  queue_.push_back(Pending{&route, std::string(static_cast<const char*>(data), size)});
  queue_bytes_ += size;
  if (queue_.size() == 1) cv_.notify_one();
}

void LiveView::set_state(const std::string& state, const std::string& verdict, double t_s) {
  std::lock_guard<std::mutex> lock(mu_);
  state_ = state;
  verdict_ = verdict;
  state_t_s_ = std::isfinite(t_s) ? t_s : 0.0;
  has_state_ = true;
  publish_state_locked(now_ns());
}

void LiveView::publish_state_locked(int64_t now) {
  if (!has_state_) return;
  const int64_t rig_us = newest_rig_us_.load(std::memory_order_relaxed);
  const bool live = state_ == "running" || state_ == "replaying";
  const double t_s = live && rig_us > 0 ? std::max(state_t_s_, static_cast<double>(rig_us) / 1e6) : state_t_s_;
  const nlohmann::json j{{"state", state_}, {"verdict", verdict_}, {"t_s", t_s}};
  server_.publish(verdict_id_, static_cast<uint64_t>(rig_us > 0 ? rig_us * 1000 : 0),
                  j.dump(-1, ' ', false, nlohmann::json::error_handler_t::replace));
  state_sent_ns_ = now;
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
    int64_t undecodable = 0, published = 0;
    for (const Pending& p : batch) {
      const std::string why = lcmjson::to_json(*p.route->type, p.bytes.data(), p.bytes.size(), &message);
      if (!why.empty()) {
        ++undecodable;
        continue;
      }
      const int64_t own = message.rig_time_us;
      const int64_t newest = newest_rig_us_.load(std::memory_order_relaxed);
      const int64_t t_us = own >= 0 ? own : (newest > 0 ? newest : 0);
      server_.publish(p.route->id, static_cast<uint64_t>(t_us) * 1000u, message.json);
      ++published;
    }
    batch.clear();
    std::lock_guard<std::mutex> lock(mu_);
    stats_.undecodable += undecodable;
    stats_.published += published;
  }
}

bool LiveView::flush(double timeout_s) {
  std::unique_lock<std::mutex> lock(mu_);
  if (!thread_.joinable()) return queue_.empty();
  return idle_cv_.wait_for(lock, std::chrono::duration<double>(timeout_s), [this] { return queue_.empty() && !busy_; });
}

void LiveView::stop() {
  {
    std::lock_guard<std::mutex> lock(mu_);
    stopping_ = true;
  }
  cv_.notify_all();
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
