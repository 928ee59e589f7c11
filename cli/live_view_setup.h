#pragma once
/// The live Foxglove view of `rig run --foxglove` and `rig view`: the server, the live view on
/// it, and the launcher's tap that feeds it.

#include <memory>
#include <string>

#include "foxglove/foxglove_server.h"
#include "foxglove/live_view.h"
#include "launcher/run_plan.h"

namespace nimble::cli {

/// The default port of the live view (Foxglove's own default).
inline constexpr uint16_t kDefaultFoxglovePort = 8765;

/// A Foxglove WebSocket server with the live view of the rig's channels on it.
struct LiveViewSession {
  std::unique_ptr<foxglove::FoxgloveServer> server;
  std::unique_ptr<foxglove::LiveView> view;

  /// Starts the view's thread and the server's.
  void start();
  /// Hands what is queued to the clients, closes them and ends the threads (once).
  void stop();
  ~LiveViewSession() { stop(); }
  /// The figures for a run summary ("live view: clients 1, sent 1234, ...").
  launcher::TapFigures figures() const;
};

/// Binds the server of `host_port` ("[HOST:]PORT", host 127.0.0.1 by default; port 0: a free
/// one) and advertises the rig's channels; serves `web_root` too if not empty. Starts no thread.
/// Prints where it listens on stderr, prefixed by `command`. The view leaves out the messages
/// beyond the physical bounds of `vehicle_file` (default: ident::default_vehicle_file()).
/// @throws std::invalid_argument / std::runtime_error naming what is wrong.
std::unique_ptr<LiveViewSession> open_live_view(const std::string& command, const std::string& host_port,
                                                const std::string& web_root = "", const std::string& vehicle_file = "");

/// Prints a one-line warning on stderr, prefixed by `command`, if `server` listens on an address
/// that is not a loopback one (0.0.0.0, ::, a network interface's): nothing is authenticated, so
/// anyone who can reach the port sees the live data and the page.
void warn_if_reachable(const std::string& command, const foxglove::FoxgloveServer& server);

/// Makes `options.tap` feed `session`: threads started when the launcher allows, every message
/// offered, the run's state and verdict on rig/verdict, the figures in the summary.
void tap_run(LiveViewSession& session, launcher::RunOptions& options);

}  // namespace nimble::cli
