/// `rig view`: a recorded run replayed live to Foxglove, Lichtblick or the dashboard page.

#include <csignal>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "cli/commands.h"
#include "cli/live_view_setup.h"
#include "ident/identify.h"
#include "contract/channels.h"
#include "ident/flight_data.h"
#include "lcmlog/lcm_log.h"
#include "lcmjson/lcm_json.h"

namespace nimble::cli {
namespace {

volatile std::sig_atomic_t g_stop = 0;
extern "C" void on_view_signal(int) { g_stop = 1; }

constexpr const char* kViewDescription =
    "Replays a rig log live on a Foxglove WebSocket server, as 'rig run --foxglove' serves a run:\n"
    "every channel as JSON with its schema, at the pace of its rig time (x --speed), stamped with\n"
    "rig time. Watch it in Foxglove or Lichtblick (Open connection -> Foxglove WebSocket ->\n"
    "ws://127.0.0.1:8765) or on the dashboard page (--web). A client that connects late gets each\n"
    "channel's last 10 s of rig time first. When the replay ends it holds the last frame (--hold, the\n"
    "default: a page opened then still shows the last 10 s) until Ctrl-C (SIGINT) or SIGTERM, or replays\n"
    "the log again and again (--loop), or exits (--exit-when-done). Without a LOG it serves the page alone.";

constexpr const char* kViewFooter =
    "Exit code: 0 replayed (or stopped by a signal), 2 bad usage, a log that cannot be read or is damaged\n"
    "(the error names the byte offset; --salvage replays up to the damage), or a port that cannot be bound.";

void sleep_until(std::chrono::steady_clock::time_point t) {
  while (!g_stop && std::chrono::steady_clock::now() < t) {
    const auto left = t - std::chrono::steady_clock::now();
    std::this_thread::sleep_for(std::min<std::chrono::steady_clock::duration>(left, std::chrono::milliseconds(50)));
  }
}

/// What a replay did.
struct Replay {
  int64_t events = 0;
  double rig_s = 0.0;  ///< rig time covered [s]
  std::string damage;  ///< salvaged: what was left out
};

/// Replays `file` into `view`, paced by rig time x `speed` (0: as fast as possible).
/// @throws ident::DataError for a damaged log (without salvage).
Replay replay(const std::string& file, bool salvage, double speed, foxglove::LiveView& view) {
  lcmlog::LcmLogReader log(file, salvage);
  lcmlog::LogEventRecord ev;
  Replay r;
  int64_t first_us = -1, rig_us = -1;
  auto start = std::chrono::steady_clock::now();
  while (!g_stop && log.next(&ev)) {
    ++r.events;
    // Rig time from the channels published at it; the others follow the newest.
    if (contract::due_in_sim_time(ev.channel)) {
      if (const lcmjson::LcmStruct* type = lcmjson::rig_type_for_channel(ev.channel)) {
        const int64_t t = lcmjson::rig_time_us(*type, ev.data.data(), ev.data.size());
        if (t >= 0 && t > rig_us) rig_us = t;
      }
    }
    if (rig_us >= 0 && first_us < 0) {
      first_us = rig_us;
      start = std::chrono::steady_clock::now();
    }
    if (speed > 0 && first_us >= 0) {
      const double due_s = static_cast<double>(rig_us - first_us) / 1e6 / speed;
      sleep_until(start + std::chrono::duration_cast<std::chrono::steady_clock::duration>(
                              std::chrono::duration<double>(due_s)));
    }
    view.offer(ev.channel, ev.data.data(), ev.data.size(), /*wait_for_room=*/true);
  }
  r.rig_s = first_us >= 0 ? static_cast<double>(rig_us - first_us) / 1e6 : 0.0;
  r.damage = log.damage();
  return r;
}

/// The dashboard's folder: the build's (NIMBLE_DASHBOARD_DIR) while it exists, else the
/// installation's, share/nimble_rig/dashboard next to the bin/ that holds rig.
std::string default_web_root() {
  if (std::filesystem::is_directory(NIMBLE_DASHBOARD_DIR)) return NIMBLE_DASHBOARD_DIR;
  std::error_code ec;
  const auto exe = std::filesystem::read_symlink("/proc/self/exe", ec);
  if (ec) return NIMBLE_DASHBOARD_DIR;
  return (exe.parent_path().parent_path() / "share" / "nimble_rig" / "dashboard").string();
}

/// Whether there is something to do and the inputs for it are there; if not, says why.
bool inputs_ok(const std::string& log_file, const std::string& web, const std::string& web_root, bool loop,
               double speed, bool salvage) {
  if (log_file.empty() && web.empty()) {
    std::cerr << "rig view: nothing to do: give a LOG to replay, or --web PORT to serve the page\n";
    return false;
  }
  if (loop && speed == 0) {
    std::cerr << "rig view: --loop replays at a pace: give --speed X with X > 0\n";
    return false;
  }
  if (!log_file.empty()) {
    try {
      lcmlog::LcmLogReader check(log_file, salvage);  // opens and checks the header now, before serving
    } catch (const std::exception& e) {
      std::cerr << "rig view: " << e.what() << "\n";
      return false;
    }
  }
  if (!web.empty() && !std::filesystem::is_directory(web_root)) {
    std::cerr << "rig view: --web-root " << web_root
              << " is not a directory (build the target 'dashboard' with the build's npm packages installed: "
                 "scripts/setup.sh; or give --web-root DIR)\n";
    return false;
  }
  return true;
}

/// Serves the dashboard page on `web`, pointing it to the replay's WebSocket server (or --foxglove's).
std::unique_ptr<foxglove::FoxgloveServer> open_page(const std::string& web, const std::string& foxglove,
                                                    const std::string& web_root, LiveViewSession* live) {
  std::unique_ptr<foxglove::FoxgloveServer> page;
  foxglove::ServerOptions o;
  uint16_t ws_port = 0;
  foxglove::parse_host_port(foxglove, "127.0.0.1", &o.host, &ws_port);
  try {
    foxglove::parse_host_port(web, o.host, &o.host, &o.port);
  } catch (const std::exception& e) {
    throw std::invalid_argument(std::string("--web: ") + e.what());
  }
  o.web_root = web_root;
  o.name = "nimble_rig view (page)";
  page = std::make_unique<foxglove::FoxgloveServer>(o);
  const std::string ws = live ? live->server->url() : "ws://" + o.host + ":" + std::to_string(ws_port);
  std::cerr << "rig view: dashboard on http://" << o.host << ":" << page->port() << "/?ws=" << ws << "\n";
  warn_if_reachable("view", *page);
  return page;
}

/// Replays the log into the live view, once or in a loop; returns the exit code (a failed replay
/// ends the command: `exit_when_done`).
int replay_to_view(LiveViewSession* live, const std::string& log_file, bool salvage, double speed, bool loop,
                   bool& exit_when_done) {
  live->view->set_state("replaying", "", 0.0);
  try {
    Replay r;
    for (int pass = 1;; ++pass) {
      r = replay(log_file, salvage, speed, *live->view);
      if (pass == 1 && !r.damage.empty()) std::cerr << "rig view: salvaged " << log_file << ": " << r.damage << "\n";
      if (!loop || g_stop || r.events == 0) break;
      if (pass == 1) {
        std::cerr << "rig view: replayed " << r.events << " events; looping until Ctrl-C\n";
      }
      // From the start again: the history of the pass before is not this one's past.
      live->view->restart();
      live->view->set_state("replaying", "pass " + std::to_string(pass + 1), 0.0);
    }
    char verdict[200];
    live->view->flush(2.0);
    const foxglove::LiveViewStats st = live->view->stats();
    std::snprintf(verdict, sizeof verdict, "%s %lld events, %.2f s of rig time%s",
                  g_stop ? "stopped after" : "replayed", static_cast<long long>(r.events), r.rig_s,
                  st.beyond_bounds > 0 ? "; messages beyond the physical bounds left out" : "");
    live->view->set_state(g_stop ? "stopped" : "done", verdict, r.rig_s);
    std::cerr << "rig view: " << verdict << "\n";
    if (st.beyond_bounds > 0) {
      std::cerr << "rig view: warning: " << log_file << ": left out: " << st.beyond_bounds_text << "\n";
    }
  } catch (const std::exception& e) {
    std::cerr << "rig view: " << e.what() << "\n";
    live->view->set_state("failed", e.what(), 0.0);
    exit_when_done = true;
    return cmdline::kExitUsage;
  }
  return 0;
}
}  // namespace

int run_view_command(const std::vector<std::string>& args) {
  std::string log_file, foxglove = std::to_string(kDefaultFoxglovePort), web_root = default_web_root();
  double speed = 1.0;
  std::string web;
  bool exit_when_done = false, salvage = false, loop = false, hold = false;
  cmdline::CommandLine cl("rig view", kViewDescription);
  cl->footer(kViewFooter);
  cl->add_option("log", log_file, "the rig log (rig run --log) to replay")->type_name("LOG.lcmlog");
  cl->add_option("--foxglove", foxglove,
                 "where to serve it: host 127.0.0.1 unless given, port 0 picks a free one (printed on stderr)")
      ->type_name("[HOST:]PORT")
      ->capture_default_str();
  cl->add_option("--speed", speed, "replay speed: 1 as flown, 2 twice as fast, 0 as fast as possible")
      ->check(CLI::NonNegativeNumber)
      ->type_name("X")
      ->capture_default_str();
  cl->add_option("--web", web,
                 "serve the dashboard page over HTTP (host: the --foxglove one unless given; port 0 picks a free "
                 "one): open http://HOST:PORT/?ws=ws://HOST:FOXGLOVE_PORT (docs/dashboard.md)")
      ->type_name("[HOST:]PORT");
  cl->add_option("--web-root", web_root, "the page's folder (default: the build's or installation's dashboard)")
      ->type_name("DIR")
      ->capture_default_str();
  CLI::Option* hold_opt = cl->add_flag(
      "--hold", hold,
      "when the replay ends, keep serving its last state: a client that connects then gets the last 10 s of "
      "rig time (the default)");
  CLI::Option* loop_opt = cl->add_flag(
      "--loop", loop, "when the replay ends, replay the log again from its start, until Ctrl-C (needs --speed > 0)");
  CLI::Option* exit_opt =
      cl->add_flag("--exit-when-done", exit_when_done, "exit once the log is replayed (default: --hold)");
  loop_opt->excludes(hold_opt)->excludes(exit_opt);
  hold_opt->excludes(exit_opt);
  cl->add_flag("--salvage", salvage, "a damaged rig log: replay the events before the damage and say what was left");
  std::string vehicle_file;
  cl->add_option("--vehicle", vehicle_file,
                 "the vehicle whose physical bounds (data_bounds) a message must keep to be shown (default " +
                     ident::default_vehicle_file() + ")")
      ->type_name("FILE");
  if (const auto done = cl.parse(args)) return *done;
  if (!inputs_ok(log_file, web, web_root, loop, speed, salvage)) return cmdline::kExitUsage;

  std::unique_ptr<LiveViewSession> live;
  std::unique_ptr<foxglove::FoxgloveServer> page;
  try {
    if (!log_file.empty()) live = open_live_view("view", foxglove, "", vehicle_file);
    if (!web.empty()) {
      page = open_page(web, foxglove, web_root, live.get());
    }
  } catch (const std::exception& e) {
    std::cerr << "rig view: " << e.what() << "\n";
    return cmdline::kExitUsage;
  }

  g_stop = 0;
  struct sigaction sa {};
  sa.sa_handler = on_view_signal;
  sigemptyset(&sa.sa_mask);
  sigaction(SIGINT, &sa, nullptr);
  sigaction(SIGTERM, &sa, nullptr);
  if (live) live->start();
  if (page) page->start();

  int code = 0;
  if (live) code = replay_to_view(live.get(), log_file, salvage, speed, loop, exit_when_done);
  if (!exit_when_done && !g_stop) {
    std::cerr << (live ? "rig view: holding the last state (a client that connects gets the last 10 s) until Ctrl-C\n"
                       : "rig view: serving until Ctrl-C\n");
    while (!g_stop) std::this_thread::sleep_for(std::chrono::milliseconds(100));
  }
  if (live) {
    live->stop();
    const launcher::TapFigures f = live->figures();
    std::cout << f.title << ":";
    for (std::size_t i = 0; i < f.values.size(); ++i) {
      std::cout << (i ? ", " : " ") << f.values[i].first << " " << f.values[i].second;
    }
    std::cout << " (" << f.note << ")\n";
  }
  if (page) page->stop();
  return code;
}

}  // namespace nimble::cli
