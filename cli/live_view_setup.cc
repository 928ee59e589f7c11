#include "cli/live_view_setup.h"

#include <iostream>

#include "ident/identify.h"

namespace nimble::cli {
namespace {
/// The nice value of the live view's threads.
constexpr int kViewerNice = 10;
}  // namespace

void LiveViewSession::start() {
  view->start();
  server->start();
}

void LiveViewSession::stop() {
  // A session whose server or view could not be made (open_live_view threw) has nothing to stop.
  if (view) {
    view->flush(1.0);
    view->stop();
  }
  if (server) server->stop();
}

launcher::TapFigures LiveViewSession::figures() const {
  const foxglove::LiveViewStats s = view->stats();
  launcher::TapFigures f;
  f.key = "live_view";
  f.title = "live view";
  f.values = {{"clients", s.server.clients_total},
              {"messages_sent", s.server.messages_sent},
              {"bytes_sent", s.server.bytes_sent},
              {"dropped", s.dropped + s.server.dropped},
              {"refused", s.server.refused + s.server.handshakes_refused},
              {"protocol_errors", s.server.protocol_errors},
              {"undecodable", s.undecodable},
              {"beyond_bounds", s.beyond_bounds}};
  f.note = server->url();
  if (!s.beyond_bounds_text.empty()) f.note += "; left out: " + s.beyond_bounds_text;
  return f;
}

std::unique_ptr<LiveViewSession> open_live_view(const std::string& command, const std::string& host_port,
                                                const std::string& web_root, const std::string& vehicle_file) {
  foxglove::ServerOptions o;
  foxglove::parse_host_port(host_port, "127.0.0.1", &o.host, &o.port);
  o.name = "nimble_rig " + command;
  o.web_root = web_root;
  // Its threads yield the CPU to the rig's processes, as the launcher itself does in real time.
  o.thread_nice = kViewerNice;
  auto session = std::make_unique<LiveViewSession>();
  session->server = std::make_unique<foxglove::FoxgloveServer>(o);
  foxglove::LiveViewOptions vo;
  vo.thread_nice = kViewerNice;
  vo.vehicle = load_vehicle(vehicle_file.empty() ? ident::default_vehicle_file() : vehicle_file);
  session->view = std::make_unique<foxglove::LiveView>(*session->server, vo);
  std::cerr << "rig " << command << ": live view on " << session->server->url()
            << " (Foxglove or Lichtblick: Open connection -> Foxglove WebSocket)\n";
  warn_if_reachable(command, *session->server);
  return session;
}

void warn_if_reachable(const std::string& command, const foxglove::FoxgloveServer& server) {
  if (server.loopback()) return;
  const std::string& h = server.host();
  std::cerr << "rig " << command << ": warning: listening on " << (h.find(':') != std::string::npos ? "[" + h + "]" : h)
            << ":" << server.port()
            << ", not a loopback address: anyone who can reach this port can see the live data and the page "
               "(nothing is authenticated; use 127.0.0.1 to keep it on this machine)\n";
}

void tap_run(LiveViewSession& session, launcher::RunOptions& options) {
  LiveViewSession* s = &session;
  options.tap.start = [s] { s->start(); };
  options.tap.message = [s](const std::string& channel, const void* data, int size) {
    s->view->offer(channel, data, static_cast<std::size_t>(size));
  };
  options.tap.state = [s](const std::string& state, const std::string& verdict, double t_s) {
    s->view->set_state(state, verdict, t_s);
  };
  options.tap.figures = [s] { return s->figures(); };
}

}  // namespace nimble::cli
