/// bench_rig: the rig's timing figures beside the machine's floors, measured in the same run.
///
///   bench_rig [scenario.yaml] [--runs N] [--json FILE] [--set key=value]...
///
/// For the scenario (default rig_configs/id_doublet_train_fast.yaml, flown on the estimator
/// with its run settings), in a private network namespace:
///  1. the floors, quiet: a bare SCHED_FIFO 1 kHz wake-up; a bare LCM chain with the hops of the
///     rig's control path (plant -> [estimator ->] controller -> plant), each hop its own
///     process on the rig's URL, CPUs and priority;
///  2. the rig in real time as shipped (`rig run --clock realtime`): control-loop latency
///     TRUTH published -> ACTUATOR_CMD received at the plant, the plant's 1 kHz wake-up jitter,
///     the estimator's latency;
///  3. the chain floor and the rig again with a busy loop on every CPU (a bounded background
///     load this bench starts and stops);
///  4. lockstep: a bare lockstep master with the rig's participants and schedule (the speed the
///     transport allows), on the CPUs the rig steps on in lockstep (run.lockstep_cpus) at the
///     default scheduler, as the rig's processes run there; then the rig in lockstep, median of
///     N runs (default 3), with the messages it exchanges per simulated second and (in its
///     summary) each participant's turnaround.
/// The real-time runs also give the control loop's latency budget: the IMU sample's age at each
/// point of the loop, each step beside its floor (the wake-up, a bare LCM hop, bench_ekf's bare
/// EKF, the controller law alone), and the processes' own work.
/// Prints a table and, with --json, the figures under fixed keys:
///   realtime.{latency_p99_us, floor_latency_p99_us, jitter_p99_us, floor_jitter_p99_us}
///   realtime.loaded.{latency_p99_us, floor_latency_p99_us, latency_p50_us, floor_latency_p50_us}
///   realtime.budget, realtime.loaded.budget: {points: [{stage, p50_us, p99_us, step_p50_us,
///     step_p99_us, floor_p50_us, floor_p99_us, floor}], work: [{stage, p50_us, p99_us}]}
///   lockstep.{speed_x, limit_speed_x, messages_per_sim_s}
/// (and more beside them). With --foxglove-client, the rig flies once more in real time with
/// `--foxglove` and one Foxglove WebSocket client (in this program) subscribed to every channel:
/// the control loop's latency p99 with that client against the quiet run without one
/// (realtime.foxglove.{latency_p99_us, ratio}; target: within 10 %).
/// Targets (docs/timing.md "Timing"): latency p99 <= 2.5x the chain floor
/// quiet and <= 4x loaded, plant jitter p99 <= 2x the wake-up floor, lockstep >= 50 % of the
/// limit. Not a test: the figures depend on the machine; the ratios to the floors travel.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <thread>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <boost/asio/ip/tcp.hpp>
#include <boost/beast/core.hpp>
#include <boost/beast/websocket.hpp>
#include <nlohmann/json.hpp>
#include <yaml-cpp/yaml.h>

#include "cmdline/args.h"
#include "contract/channels.h"
#include "controller/attitude_controller.h"
#include "transport/clock.h"
#include "core/json_line.h"
#include "bench/bench_floor.h"
#include "launcher/netns.h"
#include "launcher/run_plan.h"

namespace fs = std::filesystem;
using namespace nimble;
using namespace nimble::launcher;

namespace {

std::string self_dir() {
  std::error_code ec;
  const auto exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

/// Flies the scenario with `rig run` and returns its JSON summary.
YAML::Node fly(const std::string& scenario, const std::string& args, const std::string& dir) {
  const std::string json = dir + "/summary.json";
  fs::remove(json);
  const std::string cmd = self_dir() + "/rig run " + scenario + " --no-progress --log " + dir +
                          "/bench.lcmlog --json " + json + " " + args + " > " + dir + "/out.txt 2>&1";
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !fs::exists(json)) {
    throw std::runtime_error("'" + cmd + "' failed; see " + dir + "/out.txt");
  }
  return YAML::LoadFile(json);
}

/// The rig's real-time figures from a run summary.
struct RigRealtime {
  double latency_p50_us = 0, latency_p99_us = 0, latency_max_us = 0;
  double jitter_p50_us = 0, jitter_p99_us = 0, jitter_max_us = 0;
  double estimator_p50_us = 0, estimator_p99_us = 0;
  std::string health;
  /// The control loop's stages every process timed (timing.<process>.stages), in the loop's
  /// order: the points of the loop, then the processes' own work.
  struct Stage {
    std::string name;
    double p50_us = 0, p99_us = 0;
  };
  std::vector<Stage> stages;
  const Stage* stage(const std::string& name) const {
    for (const Stage& st : stages) {
      if (st.name == name) return &st;
    }
    return nullptr;
  }
};

RigRealtime realtime_figures(const YAML::Node& s) {
  RigRealtime r;
  const YAML::Node p = s["timing"]["plant"];
  r.latency_p50_us = p["latency_p50_us"].as<double>();
  r.latency_p99_us = p["latency_p99_us"].as<double>();
  r.latency_max_us = p["latency_max_us"].as<double>();
  r.jitter_p50_us = p["jitter_p50_us"].as<double>();
  r.jitter_p99_us = p["jitter_p99_us"].as<double>();
  r.jitter_max_us = p["jitter_max_us"].as<double>();
  if (const YAML::Node e = s["timing"]["estimator"]; e && e["latency_count"].as<long long>() > 0) {
    r.estimator_p50_us = e["latency_p50_us"].as<double>();
    r.estimator_p99_us = e["latency_p99_us"].as<double>();
  }
  if (s["realtime_health"]) r.health = s["realtime_health"]["text"].as<std::string>();
  for (const auto& process : s["timing"]) {
    if (!process.second["stages"]) continue;
    for (const auto& st : process.second["stages"]) {
      r.stages.push_back({st["stage"].as<std::string>(), st["p50_us"].as<double>(), st["p99_us"].as<double>()});
    }
  }
  return r;
}

/// Messages of every channel per simulated second in a run summary.
double messages_per_sim_s(const YAML::Node& s) {
  double n = 0.0;
  for (const auto& c : s["channels"]) n += c.second["count"].as<double>();
  return n / s["sim_time_s"].as<double>();
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0.0 : v[v.size() / 2];
}

void row(const char* label, const bench::Percentiles& p, const char* note = "") {
  std::printf("  %-50s %8.1f %8.1f %9.1f  %s\n", label, p.p50_us, p.p99_us, p.max_us, note);
}

std::string cpus_text(const std::vector<int>& cpus) {
  std::string s;
  for (int c : cpus) s += (s.empty() ? "" : ",") + std::to_string(c);
  return "[" + s + "]";
}

/// A free TCP port on 127.0.0.1 (bound and released: `rig run --foxglove` takes it next).
int free_port() {
  namespace net = boost::asio;
  net::io_context ioc;
  net::ip::tcp::acceptor a(ioc, net::ip::tcp::endpoint(net::ip::make_address("127.0.0.1"), 0));
  return a.local_endpoint().port();
}

/// A Foxglove WebSocket client on its own thread: connects to 127.0.0.1:`port` (retrying until the
/// server is up or stop()), subscribes to every advertised channel and reads until the server
/// closes. Counts what it received.
class FoxgloveClient {
 public:
  explicit FoxgloveClient(int port) : thread_([this, port] { run(port); }) {}
  ~FoxgloveClient() { stop(); }
  void stop() {
    stop_ = true;
    if (thread_.joinable()) thread_.join();
  }
  long long messages() const { return messages_; }
  long long bytes() const { return bytes_; }
  int channels() const { return channels_; }

 private:
  void run(int port) {
    namespace net = boost::asio;
    namespace beast = boost::beast;
    namespace websocket = beast::websocket;
    const auto give_up = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (!stop_ && std::chrono::steady_clock::now() < give_up) {
      net::io_context ioc;
      websocket::stream<net::ip::tcp::socket> ws(ioc);
      beast::error_code ec;
      const net::ip::tcp::endpoint server(net::ip::make_address("127.0.0.1"), static_cast<unsigned short>(port));
      ws.next_layer().connect(server, ec);
      if (ec) {
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
        continue;
      }
      ws.set_option(websocket::stream_base::decorator([](websocket::request_type& req) {
        req.set(beast::http::field::sec_websocket_protocol, "foxglove.websocket.v1");
      }));
      ws.handshake("127.0.0.1", "/", ec);
      if (ec) return;
      beast::flat_buffer buf;
      int next_id = 0;
      for (;;) {
        ws.read(buf, ec);
        if (ec) break;
        if (ws.got_text()) {
          const auto j = nlohmann::json::parse(beast::buffers_to_string(buf.data()), nullptr, false);
          if (j.is_object() && j.value("op", "") == "advertise") {
            nlohmann::json subs = nlohmann::json::array();
            for (const auto& c : j["channels"]) subs.push_back({{"id", next_id++}, {"channelId", c["id"]}});
            channels_ += static_cast<int>(subs.size());
            ws.text(true);
            ws.write(net::buffer(nlohmann::json{{"op", "subscribe"}, {"subscriptions", subs}}.dump()), ec);
          }
        } else {
          ++messages_;
          bytes_ += static_cast<long long>(buf.size());
        }
        buf.consume(buf.size());
      }
      return;  // the server closed: the run is over
    }
  }
  std::atomic<bool> stop_{false};
  std::atomic<long long> messages_{0}, bytes_{0};
  std::atomic<int> channels_{0};
  std::thread thread_;
};

/// The floors of the latency budget's stages that are not the transport's: the EKF's bare
/// predict + update per IMU sample (bench_ekf, mean), and the controller law alone.
struct StageFloors {
  double ekf_bare_us = 0.0;  ///< a textbook EKF of the same model, per IMU sample (mean)
  double ekf_own_us = 0.0;   ///< the filter's own predict + update at arrival, per IMU sample (mean)
  bench::Percentiles law;    ///< AttitudeController::step alone
};

/// Times the scenario's controller law alone on a moving input, `n` calls.
bench::Percentiles controller_law_floor(const Scenario& scenario, int n) {
  ConfigMap section = scenario.section("controller");
  const ControllerConfig config = controller_config_from(section);
  AttitudeController controller(config);
  std::vector<int64_t> ns;
  ns.reserve(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) {
    ControllerInput in;
    const double t = k / 512.0;
    in.phi_rad = 0.2 * std::sin(6.0 * t);
    in.p_radps = 1.2 * std::cos(6.0 * t);
    in.theta_rad = 0.05 * std::sin(2.0 * t);
    in.roll_sp_rad = k % 1024 < 512 ? 0.1 : -0.1;
    const int64_t t0 = transport::monotonic_ns();
    const ControllerOutput out = controller.step(in);
    ns.push_back(transport::monotonic_ns() - t0);
    if (!std::isfinite(out.delta_f_cmd_radps)) throw std::runtime_error("the controller law gave a non-finite command");
  }
  return bench::percentiles(ns);
}

/// The EKF's floors from bench_ekf (beside this program), per IMU sample at `imu_hz`.
void ekf_floors(const std::string& dir, double imu_hz, StageFloors* f) {
  const std::string json = dir + "/ekf.json";
  const std::string cmd = self_dir() + "/bench_ekf 10 --passes 3 --json " + json + " > " + dir + "/ekf.txt 2>&1";
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) throw std::runtime_error("'" + cmd + "' failed");
  const YAML::Node j = YAML::LoadFile(json);
  f->ekf_bare_us = j["floor_us_per_s"].as<double>() / imu_hz;
  f->ekf_own_us = j["own_floor_us_per_s"].as<double>() / imu_hz;
}

/// One row of the latency budget: a point of the loop, its age, the step from the point before
/// and that step's floor.
struct BudgetRow {
  std::string stage, floor_what;
  double p50_us = 0, p99_us = 0, step_p50_us = 0, step_p99_us = 0, floor_p50_us = 0, floor_p99_us = 0;
};

/// The control loop's latency budget of a real-time run on the estimate (the points every
/// process timed, in the loop's order) beside each step's floor: the wake-up for the plant's
/// publication, a bare LCM hop (the chain's round trip over its hops) for each transport step,
/// the EKF's bare predict + update for the estimator, the law alone for the controller.
std::vector<BudgetRow> latency_budget(const RigRealtime& r, const bench::Percentiles& wake,
                                      const bench::Percentiles& chain, int hops, const StageFloors& f) {
  const double hop50 = chain.p50_us / hops, hop99 = chain.p99_us / hops;
  struct Point {
    const char* stage;
    const char* floor_what;
    double floor_p50, floor_p99;
  };
  const Point points[] = {
      {"plant: IMU sample published", "bare 1 kHz wake-up", wake.p50_us, wake.p99_us},
      {"estimator: IMU sample received", "bare LCM hop (chain / hops)", hop50, hop99},
      {"estimator: ESTIMATE published", "bare EKF predict + update (mean)", f.ekf_bare_us, f.ekf_bare_us},
      {"controller: ESTIMATE received", "bare LCM hop (chain / hops)", hop50, hop99},
      {"controller: ACTUATOR_CMD published", "the law alone", f.law.p50_us, f.law.p99_us},
      {"plant: ACTUATOR_CMD received", "bare LCM hop (chain / hops)", hop50, hop99},
  };
  std::vector<BudgetRow> rows;
  double prev50 = 0.0, prev99 = 0.0;
  for (const Point& pt : points) {
    const RigRealtime::Stage* st = r.stage(pt.stage);
    if (st == nullptr) continue;
    rows.push_back({pt.stage, pt.floor_what, st->p50_us, st->p99_us, st->p50_us - prev50, st->p99_us - prev99,
                    pt.floor_p50, pt.floor_p99});
    prev50 = st->p50_us;
    prev99 = st->p99_us;
  }
  return rows;
}

void print_budget(const char* title, const std::vector<BudgetRow>& rows, const RigRealtime& r, const StageFloors& f) {
  std::printf("\nlatency budget, %s: the IMU sample's age at each point of the control loop [us]\n", title);
  std::printf("  %-38s %8s %8s  %9s %9s  %9s %9s  %s\n", "point", "age p50", "age p99", "step p50", "step p99",
              "floor p50", "floor p99", "the step's floor");
  double floor50 = 0.0, floor99 = 0.0;
  for (const BudgetRow& b : rows) {
    std::printf("  %-38s %8.1f %8.1f  %9.1f %9.1f  %9.1f %9.1f  %s\n", b.stage.c_str(), b.p50_us, b.p99_us,
                b.step_p50_us, b.step_p99_us, b.floor_p50_us, b.floor_p99_us, b.floor_what.c_str());
    floor50 += b.floor_p50_us;
    floor99 += b.floor_p99_us;
  }
  if (!rows.empty()) {
    std::printf("  %-38s %8.1f %8.1f  (the floors' sum; the loop: %.2fx at p50, %.2fx at p99)\n", "sum of the floors",
                floor50, floor99, rows.back().p50_us / floor50, rows.back().p99_us / floor99);
  }
  std::printf("  the processes' own work%*s p50      p99\n", 55, "");
  for (const RigRealtime::Stage& st : r.stages) {
    if (st.name.find("its work") == std::string::npos) continue;
    std::printf("  %-75s %8.1f %8.1f\n", st.name.c_str(), st.p50_us, st.p99_us);
  }
  std::printf(
      "  floors: EKF predict + update per IMU sample (mean) %.2f bare, %.2f the filter's own; the law alone "
      "p50 %.2f, p99 %.2f\n",
      f.ekf_bare_us, f.ekf_own_us, f.law.p50_us, f.law.p99_us);
}

OrderedJson budget_json(const std::vector<BudgetRow>& rows, const RigRealtime& r) {
  OrderedJson j = OrderedJson::object();
  j["points"] = OrderedJson::array();
  for (const BudgetRow& b : rows) {
    j["points"].push_back({{"stage", b.stage},
                           {"p50_us", b.p50_us},
                           {"p99_us", b.p99_us},
                           {"step_p50_us", b.step_p50_us},
                           {"step_p99_us", b.step_p99_us},
                           {"floor_p50_us", b.floor_p50_us},
                           {"floor_p99_us", b.floor_p99_us},
                           {"floor", b.floor_what}});
  }
  j["work"] = OrderedJson::array();
  for (const RigRealtime::Stage& st : r.stages) {
    if (st.name.find("its work") != std::string::npos) {
      j["work"].push_back({{"stage", st.name}, {"p50_us", st.p50_us}, {"p99_us", st.p99_us}});
    }
  }
  return j;
}

}  // namespace

/// The figures one bench_rig run reports.
struct Figures {
  std::string scenario;
  int hops = 0;
  bench::Percentiles wake, chain, chain_loaded;
  RigRealtime quiet, loaded;
  bench::LockstepFloor limit;
  std::size_t participants = 0;
  double speed = 0.0, rig_messages = 0.0;
  bool foxglove = false;  ///< --foxglove-client: the run with a client below
  RigRealtime with_client;
  long long client_messages = 0;
  std::vector<BudgetRow> budget_quiet, budget_loaded;  ///< the latency budgets (on the estimate)
};

/// The figures as JSON to `file`, under fixed keys. @throws std::runtime_error if it cannot be written.
void write_figures_json(const std::string& file, const Figures& f) {
  OrderedJson j;
  j["scenario"] = f.scenario;
  j["cpus"] = ::sysconf(_SC_NPROCESSORS_ONLN);
  OrderedJson& rt = j["realtime"];
  rt["latency_p99_us"] = f.quiet.latency_p99_us;
  rt["floor_latency_p99_us"] = f.chain.p99_us;
  rt["jitter_p99_us"] = f.quiet.jitter_p99_us;
  rt["floor_jitter_p99_us"] = f.wake.p99_us;
  rt["latency_p50_us"] = f.quiet.latency_p50_us;
  rt["floor_latency_p50_us"] = f.chain.p50_us;
  rt["estimator_latency_p99_us"] = f.quiet.estimator_p99_us;
  rt["chain_hops"] = f.hops;
  rt["health"] = f.quiet.health;
  rt["budget"] = budget_json(f.budget_quiet, f.quiet);
  rt["loaded"] = {{"latency_p99_us", f.loaded.latency_p99_us},       {"floor_latency_p99_us", f.chain_loaded.p99_us},
                  {"latency_p50_us", f.loaded.latency_p50_us},       {"floor_latency_p50_us", f.chain_loaded.p50_us},
                  {"jitter_p99_us", f.loaded.jitter_p99_us},         {"health", f.loaded.health},
                  {"budget", budget_json(f.budget_loaded, f.loaded)}};
  if (f.foxglove) {
    rt["foxglove"] = {{"latency_p99_us", f.with_client.latency_p99_us},
                      {"latency_p99_us_without", f.quiet.latency_p99_us},
                      {"ratio", f.with_client.latency_p99_us / f.quiet.latency_p99_us},
                      {"client_messages", f.client_messages}};
  }
  j["lockstep"] = {{"speed_x", f.speed},
                   {"limit_speed_x", f.limit.speed_x},
                   {"messages_per_sim_s", f.rig_messages},
                   {"limit_messages_per_sim_s", f.limit.messages_per_sim_s},
                   {"participants", f.participants}};
  std::ofstream out(file);
  out << json_line(j) << "\n";
  if (!out) throw std::runtime_error("cannot write " + file);
}

namespace {

/// The command line: the scenario, --runs, --json, --foxglove-client and the --set overrides
/// (kept both parsed, `extra`, and as rig arguments, `set_args`).
void add_options(cmdline::CommandLine& cl, std::string& scenario, std::string& json_file, std::vector<Override>& extra,
                 std::string& set_args, int& runs, bool& foxglove_client) {
  cl->add_option("scenario", scenario, "the scenario (default rig_configs/id_doublet_train_fast.yaml)")
      ->type_name("SCENARIO.YAML");
  cl->add_option("--runs", runs, "lockstep runs (the median is reported)")
      ->check(CLI::Range(1, 1000))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--json", json_file, "the figures as JSON to FILE, under fixed keys")->type_name("FILE");
  cl->add_flag("--foxglove-client", foxglove_client,
               "fly once more in real time with --foxglove and one client subscribed to every channel: the "
               "control loop's latency p99 with it against without (target: within 10 %)");
  cmdline::each_value(cl->add_option("--set", "override one scenario value in every rig run; repeatable")
                          ->type_name("KEY.PATH=VALUE")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&](const std::string& v) {
                        extra.push_back(parse_override(v));
                        set_args += " --set " + v;
                      });
}

/// Flies the rig once more in real time with --foxglove and one client on every channel, and
/// prints its loop latency against the quiet run's; `client_messages` gets what the client received.
RigRealtime fly_with_client(const std::string& scenario, const std::string& set_args, const std::string& dir,
                            const RigRealtime& quiet, long long& client_messages) {
  RigRealtime with_client;
  const int port = free_port();
  FoxgloveClient client(port);
  with_client =
      realtime_figures(fly(scenario, "--clock realtime --foxglove 127.0.0.1:" + std::to_string(port) + set_args, dir));
  client.stop();
  client_messages = client.messages();
  row("rig + live view, 1 client on every channel: loop latency",
      {with_client.latency_p50_us, with_client.latency_p99_us, with_client.latency_max_us, 0});
  std::printf("  the client subscribed to %d channels and received %lld messages (%.1f MB)\n", client.channels(),
              client_messages, static_cast<double>(client.bytes()) / 1e6);
  std::printf("  latency p99 with the client %.1f us, without %.1f us: ratio %.3f (target <= 1.10)\n",
              with_client.latency_p99_us, quiet.latency_p99_us, with_client.latency_p99_us / quiet.latency_p99_us);
  std::printf("  %s\n", with_client.health.c_str());
  return with_client;
}

/// The lockstep figures: the bare floor with the rig's participants and schedule, and the rig's.
struct Lockstep {
  bench::LockstepFloor limit;
  std::size_t participants = 0;
  double speed = 0.0;         ///< the rig's, median of the runs [x real time]
  double rig_messages = 0.0;  ///< per simulated second
};

/// Measures the lockstep floor, then flies the rig in lockstep `runs` times; prints both.
Lockstep measure_lockstep(const RunOptions& ro, const std::string& scenario, const std::string& set_args,
                          const std::string& dir, const std::string& url, int runs) {
  RunOptions lo = ro;
  lo.clock = kClockLockstep;
  const RunPlan lplan = load_run_plan(lo);
  const auto participants = contract::lockstep_participants(
      lplan.rates, contract::RunShape{true, lplan.logger_period_ms, lplan.scenario.processes.size()});
  const int64_t step_ns = std::llround(1e9 / lplan.rates.plant_hz);
  // The floor as the rig steps in lockstep: on run.lockstep_cpus, at the default scheduler (the
  // rig's processes take SCHED_FIFO in real time only).
  bench::FloorSettings lockstep_like;
  lockstep_like.cpus = lplan.launch.lockstep_cpus;
  const bench::LockstepFloor limit = bench::lockstep_floor(url, step_ns, participants, 3.0, lockstep_like);
  std::vector<double> speeds;
  double rig_messages = 0.0;
  YAML::Node last;
  for (int i = 0; i < runs; ++i) {
    last = fly(scenario, "--clock lockstep" + set_args, dir);
    speeds.push_back(last["speed_x_realtime"].as<double>());
    rig_messages = messages_per_sim_s(last);
  }
  const double speed = median(speeds);
  std::vector<RigRealtime::Stage> turnarounds;  // of the last run: each participant's, the master's own step
  for (const auto& process : last["timing"]) {
    if (!process.second["stages"]) continue;
    for (const auto& st : process.second["stages"]) {
      const std::string name = st["stage"].as<std::string>();
      if (name.rfind("lockstep: ", 0) == 0) {
        turnarounds.push_back({name, st["p50_us"].as<double>(), st["p99_us"].as<double>()});
      }
    }
  }
  std::printf("\nlockstep%*s speed [x real time]  messages per simulated s\n", 44, "");
  std::printf("  %-50s %10.1f %16.0f\n",
              ("floor: bare master + " + std::to_string(participants.size()) + " participants, rig schedule").c_str(),
              limit.speed_x, limit.messages_per_sim_s);
  std::printf("  %-50s %10.1f %16.0f   (median of %d; %.0f %% of the floor)\n", "rig", speed, rig_messages, runs,
              100.0 * speed / limit.speed_x);
  std::printf(
      "  a step's wall time on average: the rig %.1f us, the floor %.1f us; the last run's turnarounds "
      "[us]:\n",
      1e-3 * static_cast<double>(step_ns) / speed, 1e-3 * static_cast<double>(step_ns) / limit.speed_x);
  for (const RigRealtime::Stage& st : turnarounds) {
    std::printf("    %-82s p50 %7.1f  p99 %7.1f\n", st.name.c_str(), st.p50_us, st.p99_us);
  }
  return Lockstep{limit, participants.size(), speed, rig_messages};
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenario = std::string(RIG_SOURCE_DIR) + "/rig_configs/id_doublet_train_fast.yaml";
  std::string json_file;
  std::vector<Override> extra;  // --set key=value, applied to every rig run
  std::string set_args;
  int runs = 3;
  bool foxglove_client = false;
  cmdline::CommandLine cl(
      "bench_rig",
      "The rig's timing figures beside the machine's floors, measured in the same run, in a private\n"
      "network namespace: real time quiet and loaded (control-loop latency, plant wake-up jitter)\n"
      "against a bare SCHED_FIFO wake-up and a bare LCM chain, and lockstep against a bare lockstep\n"
      "master.");
  cl->footer("Not a test: the figures depend on the machine; the ratios to the floors travel.");
  add_options(cl, scenario, json_file, extra, set_args, runs, foxglove_client);
  if (const auto done = cl.parse(argc, argv)) return *done;
  try {
    RunOptions ro;
    ro.scenario_file = scenario;
    ro.clock = kClockRealtime;
    ro.overrides = extra;
    const RunPlan plan = load_run_plan(ro);
    const ProcessRunOptions run = process_run_options(plan.scenario);
    const bool on_estimate = run.controller_input == "estimate";
    const int hops = on_estimate ? 3 : 2;

    // Every floor process lives in this private namespace; the rig makes its own inside it.
    const NamespaceResult ns = enter_private_network_namespace();
    if (!ns.ok) throw std::runtime_error("cannot create a private network namespace: " + ns.detail);
    const std::string url = kNamespaceLcmUrl;
    // The floors run where the rig runs (its CPUs), under SCHED_FIFO (the rig's priority, or 80
    // as cyclictest -p 80 if the rig has none): the best this machine allows there.
    bench::FloorSettings rig_like;
    rig_like.priority = run.realtime_priority > 0 ? run.realtime_priority : 80;
    rig_like.cpus = plan.launch.rig_cpus;
    const std::string dir = (fs::temp_directory_path() / ("bench_rig_" + std::to_string(::getpid()))).string();
    fs::create_directories(dir);

    std::printf("bench_rig: %s\n", plan.scenario.name.c_str());
    std::printf(
        "machine: %ld CPUs online; rig settings: CPUs %s, SCHED_FIFO priority %d%s, spin %d us, controller "
        "on the %s\n",
        ::sysconf(_SC_NPROCESSORS_ONLN), cpus_text(rig_like.cpus).c_str(), run.realtime_priority,
        run.realtime_priority == 0 ? " (off)" : "", run.spin_us, run.controller_input.c_str());
    std::printf("\nreal time, quiet machine%*s p50 [us] p99 [us]  max [us]\n", 28, "");
    const bench::Percentiles wake = bench::wake_up_floor(1000.0, 5.0, rig_like);
    const std::string wake_label = "floor: bare 1 kHz wake-up, SCHED_FIFO " + std::to_string(rig_like.priority);
    row(wake_label.c_str(), wake);
    const bench::Percentiles chain = bench::lcm_chain_floor(url, hops, 1000.0, 5.0, 256, rig_like);
    const std::string chain_label = "floor: bare LCM chain, " + std::to_string(hops) + " hops, 1 kHz, SCHED_FIFO " +
                                    std::to_string(rig_like.priority);
    row(chain_label.c_str(), chain);
    const RigRealtime quiet = realtime_figures(fly(scenario, "--clock realtime" + set_args, dir));
    row("rig: plant 1 kHz wake-up jitter", {quiet.jitter_p50_us, quiet.jitter_p99_us, quiet.jitter_max_us, 0});
    row("rig: control loop TRUTH -> ACTUATOR_CMD at the plant",
        {quiet.latency_p50_us, quiet.latency_p99_us, quiet.latency_max_us, 0});
    if (on_estimate)
      row("rig: estimator, IMU sample -> ESTIMATE", {quiet.estimator_p50_us, quiet.estimator_p99_us, 0, 0});
    std::printf("  %s\n", quiet.health.c_str());
    StageFloors stage_floors;
    std::vector<BudgetRow> budget_quiet, budget_loaded;
    if (on_estimate) {
      stage_floors.law = controller_law_floor(plan.scenario, 20000);
      ekf_floors(dir, plan.scenario.expected_rate(contract::channels::kImu), &stage_floors);
      budget_quiet = latency_budget(quiet, wake, chain, hops, stage_floors);
      print_budget("quiet", budget_quiet, quiet, stage_floors);
    }

    RigRealtime with_client;
    long long client_messages = 0;
    if (foxglove_client) with_client = fly_with_client(scenario, set_args, dir, quiet, client_messages);

    std::printf("\nreal time, a busy loop on every CPU%*s p50 [us] p99 [us]  max [us]\n", 17, "");
    bench::Percentiles chain_loaded;
    RigRealtime loaded;
    {
      bench::CpuHog hog(120.0);
      chain_loaded = bench::lcm_chain_floor(url, hops, 1000.0, 5.0, 256, rig_like);
      loaded = realtime_figures(fly(scenario, "--clock realtime" + set_args, dir));
    }
    row(chain_label.c_str(), chain_loaded);
    row("rig: plant 1 kHz wake-up jitter", {loaded.jitter_p50_us, loaded.jitter_p99_us, loaded.jitter_max_us, 0});
    row("rig: control loop TRUTH -> ACTUATOR_CMD at the plant",
        {loaded.latency_p50_us, loaded.latency_p99_us, loaded.latency_max_us, 0});
    std::printf("  %s\n", loaded.health.c_str());
    if (on_estimate) {
      budget_loaded = latency_budget(loaded, wake, chain_loaded, hops, stage_floors);
      print_budget("a busy loop on every CPU", budget_loaded, loaded, stage_floors);
    }

    const Lockstep lockstep = measure_lockstep(ro, scenario, set_args, dir, url, runs);
    const bench::LockstepFloor& limit = lockstep.limit;
    const double speed = lockstep.speed;

    const double r_quiet = quiet.latency_p99_us / chain.p99_us, r_loaded = loaded.latency_p99_us / chain_loaded.p99_us;
    std::printf(
        "\nlatency p50 against the chain's: quiet %.2f, loaded %.2f (target <= 1.4); p99 quiet %.2f, loaded %.2f "
        "(target <= 1.6)\n",
        quiet.latency_p50_us / chain.p50_us, loaded.latency_p50_us / chain_loaded.p50_us, r_quiet, r_loaded);
    const double r_jitter = quiet.jitter_p99_us / wake.p99_us;
    std::printf(
        "\nratios to the floors (targets): latency p99 quiet %.2f (<= 2.5), loaded %.2f (<= 4); plant jitter "
        "p99 %.2f (<= 2); lockstep %.0f %% of the limit (>= 50 %%)\n",
        r_quiet, r_loaded, r_jitter, 100.0 * speed / limit.speed_x);

    if (!json_file.empty()) {
      write_figures_json(json_file, Figures{plan.scenario.name, hops, wake, chain, chain_loaded, quiet, loaded, limit,
                                            lockstep.participants, speed, lockstep.rig_messages, foxglove_client,
                                            with_client, client_messages, budget_quiet, budget_loaded});
    }
    fs::remove_all(dir);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_rig: %s\n", e.what());
    return 1;
  }
  return 0;
}
