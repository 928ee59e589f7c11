#pragma once
/// The live view of a run or of a replayed log on a Foxglove WebSocket server: every channel of
/// the rig's contract (contract/channels.h) is advertised under its name with the JSON Schema of
/// its LCM type (lcmjson/lcm_json.h); its messages go out as JSON, stamped with the rig's
/// simulated time. One more channel, `rig/verdict`, carries the run's state and verdict.
///
/// offer() is called where the messages are recorded (the launcher's recording thread, or the
/// replay loop): it does not decode anything. It copies the bytes of a message into a bounded
/// queue (a full queue drops the message and counts it) and returns; the live view's own thread
/// keeps them in the channel's history and decodes those that some client subscribes to, handing
/// the JSON to the server, which queues it for each subscribed client (foxglove_server.h, bounded
/// again per client).
///
/// The history: each channel keeps the LCM bytes of its messages of the last `history_s` of rig
/// time (bounded in bytes too), so that a client that subscribes late (a page opened after the
/// replay ended) gets them first: the server holds a new subscription (FoxgloveServer::
/// set_subscribe_handler), the request joins the queue behind the messages offered before it,
/// and the live view's thread answers it with the channel's history, decoded then, in the order
/// offered; live messages follow, without a gap or a repetition. Without history (history_s 0),
/// only messages some client subscribes to are copied, and a client gets what is published from
/// the moment it subscribes.

#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <deque>
#include <map>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "core/data_bounds.h"
#include "core/vehicle.h"
#include "foxglove/foxglove_server.h"

namespace nimble::lcmjson {
struct LcmStruct;
struct JsonMessage;
}  // namespace nimble::lcmjson

namespace nimble::foxglove {

/// The topic of the run's state and verdict, and its schema's name.
inline constexpr const char* kVerdictTopic = "rig/verdict";
inline constexpr const char* kVerdictSchemaName = "nimble.run_verdict";

struct LiveViewOptions {
  /// The queue between offer() and the decoding thread: at most this many bytes and messages.
  std::size_t max_queue_bytes = 4u << 20;
  std::size_t max_queue_messages = 8192;
  /// The nice value of the decoding thread (0: as the thread that calls start()).
  int thread_nice = 0;
  /// Each channel's history for clients that subscribe late: its messages of the last
  /// `history_s` of rig time (before the newest rig time seen on any channel), at most
  /// `history_bytes` per channel (LCM bytes and the bookkeeping of each message; the oldest
  /// leave first). 0: no history. The defaults cover the dashboard's 10 s window
  /// (docs/dashboard.md): 10 s of TRUTH at 1 kHz take 3 MiB.
  double history_s = 10.0;
  std::size_t history_bytes = 6u << 20;
  /// Check every message against this vehicle's physical bounds (contract/message_bounds.h): a
  /// message with a field beyond them is neither sent nor kept, and is counted and named
  /// (LiveViewStats::beyond_bounds, and `beyond_bounds` on rig/verdict). None: not checked.
  std::optional<Vehicle> vehicle;
};

/// What the live view counted, with the server's own figures.
struct LiveViewStats {
  int64_t offered = 0;  ///< messages offered on a channel with a subscriber
  int64_t dropped = 0;  ///< of those, dropped because the live view's queue was full
  /// Messages of channels without a subscriber that the history missed: the queue was full (a
  /// run in process can outpace the live view's thread; a replay waits instead).
  int64_t history_dropped = 0;
  int64_t undecodable = 0;         ///< bytes that were not a message of the channel's type (not sent)
  int64_t beyond_bounds = 0;       ///< messages with a field beyond the vehicle's bounds (not sent, not kept)
  std::string beyond_bounds_text;  ///< which: channel, field, time and count (BoundsTally::text()); "" if none
  int64_t published = 0;           ///< messages handed to the server live
  int64_t backlogs = 0;            ///< histories handed to clients that subscribed
  int64_t backlog_messages = 0;    ///< messages in those
  ServerStats server;
};

class LiveView {
 public:
  /// Advertises the contract's channels and `rig/verdict` on `server` (which must outlive this).
  /// Starts no thread: start() does.
  explicit LiveView(FoxgloveServer& server, LiveViewOptions options = {});
  /// stop().
  ~LiveView();
  LiveView(const LiveView&) = delete;
  LiveView& operator=(const LiveView&) = delete;

  /// Starts the decoding thread (once). Messages offered before are queued.
  void start();
  /// One message of `channel` (LCM bytes). Cheap; never blocks on a client or on decoding.
  /// Channels outside the contract are ignored. When the queue is full the message is dropped
  /// and counted, or, with `wait_for_room` (a replay, which sets its own pace), offer() waits
  /// until the live view's thread has taken the queue (it never waits for a client).
  void offer(const std::string& channel, const void* data, std::size_t size, bool wait_for_room = false);
  /// The run's state ("running", "done", ...), its verdict text ("" until there is one) and the
  /// simulated time [s]; sent on `rig/verdict` now and again every second (for clients that
  /// subscribe later). While the state is "running" or "replaying", the repeats carry the newest
  /// rig time seen.
  void set_state(const std::string& state, const std::string& verdict, double t_s);
  /// Rig time starts again (a replay from its start): the histories offered so far are
  /// forgotten and the newest rig time is forgotten.
  void restart();
  /// Decodes and publishes what is queued, then ends the thread. offer() after stop() is ignored.
  void stop();
  /// Waits until everything offered so far has been handed to the server (or `timeout_s`).
  bool flush(double timeout_s = 2.0);

  /// The newest rig (simulated) time seen in any message [us], -1 before the first.
  int64_t newest_rig_time_us() const { return newest_rig_us_.load(std::memory_order_relaxed); }
  LiveViewStats stats() const;

  /// The channel id of `topic` on the server (0 if it has none).
  uint32_t channel_id(const std::string& topic) const;

 private:
  struct Route {
    uint32_t id = 0;
    const lcmjson::LcmStruct* type = nullptr;
    bool tracks_rig_time = false;  ///< published at rig time, which sits at a fixed offset: read on offer()
    std::string channel;
    bool bounded = false;  ///< its type has fields with a physical bound (checked on the thread)
  };
  /// An item of the queue: a message of `route`, a new subscription to answer, or a restart.
  struct Pending {
    const Route* route = nullptr;  ///< a message; nullptr: a subscription or a restart
    std::string bytes;
    int64_t stamp_us = -1;  ///< its rig time: its own, or the newest seen when it was offered
    bool restart = false;
    FoxgloveServer::NewSubscription subscription;
  };
  /// A message kept in a channel's history.
  struct Kept {
    int64_t stamp_us = -1;
    std::string bytes;
  };
  struct History {
    std::deque<Kept> kept;
    std::size_t bytes = 0;
  };
  void run();
  /// On the thread: true (counted) if the message has a field beyond the vehicle's bounds.
  bool beyond_bounds(const Route& route, int64_t stamp_us, const std::string& bytes);
  void publish_state_locked(int64_t now_ns);
  std::string state_json_locked() const;
  void on_subscribe(const FoxgloveServer::NewSubscription& s);
  /// On the thread: the backlog of a new subscription.
  void answer(const FoxgloveServer::NewSubscription& s, lcmjson::JsonMessage* scratch);
  void keep(const Route& route, int64_t stamp_us, std::string bytes);
  bool has_history() const { return options_.history_s > 0 && options_.history_bytes > 0; }

  FoxgloveServer& server_;
  LiveViewOptions options_;
  std::map<std::string, Route> routes_;     // fixed after construction
  std::map<uint32_t, const Route*> by_id_;  // fixed after construction
  std::map<uint32_t, History> history_;     // the thread's only (channel id -> its history)
  uint32_t verdict_id_ = 0;
  std::atomic<int64_t> newest_rig_us_{-1};

  mutable std::mutex mu_;            // everything below
  std::condition_variable cv_;       // work for the thread, or stop
  std::condition_variable idle_cv_;  // the thread went idle (flush())
  std::condition_variable room_cv_;  // the thread took the queue (offer() waiting for room)
  std::deque<Pending> queue_;
  std::size_t queue_bytes_ = 0;
  bool started_ = false, stopping_ = false, busy_ = false;
  std::string state_, verdict_;
  double state_t_s_ = 0.0;
  bool has_state_ = false;
  int64_t state_sent_ns_ = 0;
  LiveViewStats stats_;
  std::optional<BoundsTally> beyond_;  ///< the thread's own: messages beyond the vehicle's bounds
  std::thread thread_;
};

}  // namespace nimble::foxglove
