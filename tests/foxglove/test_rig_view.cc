/// `rig view`: a log replayed live to a Foxglove client, a client that connects after the replay
/// ended (the last 10 s), --loop, a damaged log named by its offset, --salvage, bad options, the
/// page server (--web) refusing paths out of its root.

#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <regex>
#include <string>
#include <vector>

#include "contract/channels.h"
#include "foxglove/live_view.h"
#include "tests/foxglove/http_test_client.h"
#include "tests/foxglove/ws_test_client.h"
#include "tests/support/run_rig.h"
#include "tests/support/scratch.h"

using namespace nimble;
using namespace nimble::foxglove;
using namespace nimble::foxglove::test;

namespace {

/// A hover log of `seconds` flown in process (made once per test program and length).
std::string flown_log(int seconds) {
  const std::string file = nimble::test::scratch_file("view", "hover" + std::to_string(seconds) + ".lcmlog");
  if (std::filesystem::exists(file)) return file;
  const auto r = nimble::test::run_rig("run " + std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml" +
                                       " --clock inprocess --set duration_s=" + std::to_string(seconds) +
                                       " --no-progress --log " + file);
  REQUIRE(r.exit_code == 0);
  return file;
}

/// A 2 s hover log.
const std::string& hover_log() {
  static const std::string log = flown_log(2);
  return log;
}

/// `rig view` running with `args` (its stderr in `err`, stdout in `out`), and its port.
struct ViewProcess {
  pid_t pid = -1;
  uint16_t port = 0;
  std::string err, out;

  /// Starts it and waits until its stderr has the line `ready` (a regular expression) and the
  /// server's port.
  ViewProcess(const std::vector<std::string>& args, const std::string& ready) {
    static int n = 0;
    err = hover_log() + ".view" + std::to_string(++n) + ".err";
    out = hover_log() + ".view" + std::to_string(n) + ".out";
    std::vector<std::string> argv{RIG_BIN, "view"};
    argv.insert(argv.end(), args.begin(), args.end());
    pid = ::fork();
    if (pid == 0) {
      std::freopen(err.c_str(), "w", stderr);
      std::freopen(out.c_str(), "w", stdout);
      std::vector<char*> a;
      for (auto& s : argv) a.push_back(s.data());
      a.push_back(nullptr);
      ::execv(RIG_BIN, a.data());
      ::_exit(127);
    }
    const std::regex line("live view on ws://127\\.0\\.0\\.1:([0-9]+)");
    const std::regex done(ready);
    REQUIRE(eventually(
        [&] {
          std::smatch m;
          const std::string text = nimble::test::slurp(err);
          if (!std::regex_search(text, m, line) || !std::regex_search(text, done)) return false;
          port = static_cast<uint16_t>(std::stoi(m[1]));
          return true;
        },
        10.0));
  }
  /// SIGINT (it keeps serving until told), then its exit code (-1: not an exit).
  int stop() {
    ::kill(pid, SIGINT);
    int status = 0;
    ::waitpid(pid, &status, 0);
    pid = -1;
    return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
  }
  ~ViewProcess() {
    if (pid > 0) stop();
  }
};

/// Connects `c` to a rig view on `port` and subscribes to `topics` (subscription i + 1 for
/// topics[i]).
void subscribe(TestClient& c, uint16_t port, const std::vector<std::string>& topics) {
  REQUIRE_FALSE(c.connect(port, kSubprotocolV1));
  c.read_json();
  const json ad = c.read_json();
  json subs = json::array();
  for (std::size_t i = 0; i < topics.size(); ++i) {
    for (const auto& ch : ad["channels"]) {
      if (ch["topic"] == topics[i]) subs.push_back({{"id", i + 1}, {"channelId", ch["id"]}});
    }
  }
  REQUIRE(subs.size() == topics.size());
  c.send_text(json{{"op", "subscribe"}, {"subscriptions", subs}}.dump());
}

}  // namespace

TEST_CASE("rig view: a damaged log is an error naming its offset, --salvage replays up to it", "[foxglove][view]") {
  const std::string cut = hover_log() + ".cut";
  {
    std::ifstream in(hover_log(), std::ios::binary);
    std::string bytes((std::istreambuf_iterator<char>(in)), {});
    std::ofstream(cut, std::ios::binary) << bytes.substr(0, bytes.size() / 2);
  }
  auto r = nimble::test::run_rig("view " + cut + " --foxglove 127.0.0.1:0 --speed 0 --exit-when-done");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("damaged at byte"));
  r = nimble::test::run_rig("view " + cut + " --foxglove 127.0.0.1:0 --speed 0 --exit-when-done --salvage");
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.err, Catch::Contains("salvaged"));
  CHECK_THAT(r.out, Catch::Contains("live view: clients 0"));
}

TEST_CASE("rig view and rig run: a live view port in use is named, exit 2, not a crash", "[foxglove][view]") {
  // A port this test holds, listening.
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  REQUIRE(fd >= 0);
  sockaddr_in a{};
  a.sin_family = AF_INET;
  a.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  REQUIRE(::bind(fd, reinterpret_cast<sockaddr*>(&a), sizeof a) == 0);
  REQUIRE(::listen(fd, 1) == 0);
  socklen_t len = sizeof a;
  REQUIRE(::getsockname(fd, reinterpret_cast<sockaddr*>(&a), &len) == 0);
  const std::string busy = "127.0.0.1:" + std::to_string(ntohs(a.sin_port));
  auto r = nimble::test::run_rig("view " + hover_log() + " --foxglove " + busy + " --speed 0 --exit-when-done");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("cannot listen on " + busy));
  r = nimble::test::run_rig("run " + std::string(RIG_SOURCE_DIR) +
                            "/rig_configs/hover.yaml --clock inprocess --set duration_s=1 --no-progress --foxglove " +
                            busy);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--foxglove " + busy + ": cannot listen on " + busy));
  ::close(fd);
}

TEST_CASE("rig view: bad options are usage errors", "[foxglove][view]") {
  CHECK(nimble::test::run_rig("view /no/such.lcmlog --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --foxglove 70000 --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --speed -1 --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --loop --speed 0").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --loop --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --hold --exit-when-done").exit_code == 2);
  const auto r = nimble::test::run_rig("view " + hover_log() + " --web 0 --web-root /no/such/dir --exit-when-done");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--web-root"));
}

TEST_CASE("rig view: a client gets the log's TRUTH at rig time and the replay's end on rig/verdict",
          "[foxglove][view]") {
  ViewProcess view({hover_log(), "--foxglove", "127.0.0.1:0", "--speed", "0.5"}, "live view on");
  TestClient c;
  subscribe(c, view.port, {contract::channels::kTruth, kVerdictTopic});
  int truths = 0;
  bool in_order = true, done = false;
  uint64_t last_ts = 0;
  std::string frame, payload, final_state;
  bool text = false;
  while (!done && c.read(&frame, &text, 5.0)) {
    uint32_t sub = 0;
    uint64_t ts = 0;
    if (text || !parse_message_data(frame, &sub, &ts, &payload)) continue;
    const json m = json::parse(payload);
    if (sub == 1) {
      ++truths;
      in_order = in_order && ts >= last_ts && ts == static_cast<uint64_t>(m["utime"].get<int64_t>()) * 1000u;
      last_ts = ts;
    } else if (m["state"] == "done") {
      done = true;
      final_state = m["verdict"];
    }
  }
  CHECK(view.stop() == 0);  // it keeps serving after the replay until told
  CHECK(done);
  CHECK_THAT(final_state, Catch::StartsWith("replayed"));
  // Of 2000 at 1 kHz, replayed at half speed (4 s): the client, subscribed within a second or so,
  // gets them all, the first ones from the history.
  CHECK(truths > 1900);
  CHECK(in_order);
}

TEST_CASE("rig view --web: //etc/passwd and other paths out of the root are refused, a warning off loopback",
          "[foxglove][view][resource]") {
  const std::filesystem::path base = nimble::test::scratch_dir("view_web");
  std::filesystem::create_directories(base / "root");
  std::ofstream(base / "root" / "index.html") << "<html>page</html>";
  const std::string token = "SECRET-" + std::to_string(::getpid());
  std::ofstream(base / "secret.txt") << token;
  const std::string root = (base / "root").string(), err = (base / "view.err").string();
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen(err.c_str(), "w", stderr);
    std::freopen("/dev/null", "w", stdout);
    ::execl(RIG_BIN, RIG_BIN, "view", "--web", "127.0.0.1:0", "--web-root", root.c_str(), nullptr);
    ::_exit(127);
  }
  int port = 0;
  const std::regex line("dashboard on http://127\\.0\\.0\\.1:([0-9]+)/");
  REQUIRE(eventually(
      [&] {
        std::smatch m;
        const std::string text = nimble::test::slurp(err);
        if (!std::regex_search(text, m, line)) return false;
        port = std::stoi(m[1]);
        return true;
      },
      10.0));
  const std::vector<std::string> targets = {"//etc/passwd",
                                            "/../../../../etc/passwd",
                                            "/%2e%2e/%2e%2e/%2e%2e/etc/passwd",
                                            "/..%2f..%2f..%2fetc%2fpasswd",
                                            "http://127.0.0.1//etc/passwd",
                                            "/" + base.string() + "/secret.txt",
                                            "/../secret.txt",
                                            "/%2E%2e/secret.txt",
                                            "/%252e%252e/secret.txt",
                                            "/%c0%ae%c0%ae/secret.txt",
                                            "/..%5csecret.txt",
                                            "/%00/etc/passwd"};
  for (const std::string& target : targets) {
    INFO(target);
    const HttpAnswer a = http_request(static_cast<uint16_t>(port), "GET", target);
    CHECK((a.status == 400 || a.status == 404));
    CHECK(a.raw.find("root:") == std::string::npos);
    CHECK(a.raw.find(token) == std::string::npos);
  }
  const HttpAnswer page = http_request(static_cast<uint16_t>(port), "GET", "/");
  CHECK(page.status == 200);
  CHECK(page.body == "<html>page</html>");
  ::kill(pid, SIGINT);
  int status = 0;
  ::waitpid(pid, &status, 0);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(nimble::test::slurp(err).find("warning") == std::string::npos);
  // On every address: served, with one line that says who can see it.
  const auto r = nimble::test::run_rig("view --web 0.0.0.0:0 --web-root " + root + " --exit-when-done");
  CHECK(r.exit_code == 0);
  CHECK_THAT(r.err, Catch::Contains("rig view: warning: listening on 0.0.0.0:") &&
                        Catch::Contains("anyone who can reach this port can see the live data and the page"));
  std::filesystem::remove_all(base);
}

TEST_CASE("rig view: a client that connects after the replay ended gets the last 10 s of rig time",
          "[foxglove][view]") {
  // 12 s flown, replayed as fast as it reads; it holds the last state by default.
  ViewProcess view({flown_log(12), "--foxglove", "127.0.0.1:0", "--speed", "0"}, "holding the last state");
  TestClient c;
  subscribe(c, view.port, {contract::channels::kTruth, contract::channels::kEstimate, kVerdictTopic});
  std::vector<int64_t> truth, estimate;
  std::vector<std::string> verdicts;
  std::string frame, payload;
  bool text = false;
  // The histories come first; rig/verdict repeats every second: two of them and all is there.
  while (verdicts.size() < 2 && c.read(&frame, &text, 3.0)) {
    uint32_t sub = 0;
    uint64_t ts = 0;
    if (text || !parse_message_data(frame, &sub, &ts, &payload)) continue;
    const json m = json::parse(payload);
    if (sub == 1) {
      CHECK(ts == static_cast<uint64_t>(m["utime"].get<int64_t>()) * 1000u);
      truth.push_back(m["utime"].get<int64_t>());
    } else if (sub == 2) {
      estimate.push_back(m["imu_utime"].get<int64_t>());
    } else {
      verdicts.push_back(m["state"].get<std::string>() + ": " + m["verdict"].get<std::string>());
    }
  }
  const int code = view.stop();
  REQUIRE(verdicts.size() == 2);
  CHECK_THAT(verdicts[0], Catch::StartsWith("done: replayed"));
  // TRUTH at 1 kHz: one run, 1 ms apart, that ends at the flight's end and spans 10 s.
  REQUIRE(truth.size() > 1000);
  const int64_t span = truth.back() - truth.front();
  INFO("TRUTH from " << truth.front() << " to " << truth.back() << " us, " << truth.size() << " messages");
  CHECK(truth.back() >= 11990000);
  CHECK(span >= 9990000);
  CHECK(span <= 10000000);
  CHECK(truth.size() == static_cast<std::size_t>(span / 1000 + 1));
  bool steps = true;
  for (std::size_t i = 1; i < truth.size(); ++i) steps = steps && truth[i] - truth[i - 1] == 1000;
  CHECK(steps);
  // ESTIMATE too: the same 10 s, in order.
  REQUIRE(estimate.size() > 1000);
  CHECK(estimate.back() - estimate.front() <= 10000000);
  CHECK(estimate.back() - estimate.front() >= 9900000);
  CHECK(std::is_sorted(estimate.begin(), estimate.end()));
  CHECK(code == 0);
  const std::string out = nimble::test::slurp(view.out);
  CHECK_THAT(out, Catch::Contains("live view: clients 1"));
  CHECK_THAT(out, Catch::Contains("dropped 0"));
}

TEST_CASE("rig view --loop: the replay starts again, and the history with it", "[foxglove][view]") {
  // 2 s replayed at 4x: a pass every half second.
  ViewProcess view({hover_log(), "--foxglove", "127.0.0.1:0", "--speed", "4", "--loop"}, "looping until Ctrl-C");
  TestClient c;
  subscribe(c, view.port, {contract::channels::kTruth, kVerdictTopic});
  int64_t last = -1, restarts = 0, after = 0;
  bool in_order = true;
  std::string frame, payload, pass;
  bool text = false;
  // Until a new pass has run for 0.5 s of rig time.
  while (after < 500 && c.read(&frame, &text, 3.0)) {
    uint32_t sub = 0;
    uint64_t ts = 0;
    if (text || !parse_message_data(frame, &sub, &ts, &payload)) continue;
    const json m = json::parse(payload);
    if (sub == 2) {
      if (m["verdict"].get<std::string>().rfind("pass ", 0) == 0) pass = m["verdict"];
      continue;
    }
    const int64_t t = m["utime"].get<int64_t>();
    if (last >= 0 && t < last) {
      ++restarts;
      in_order = in_order && t <= 1000;  // from the log's start
    } else if (last >= 0) {
      in_order = in_order && t == last + 1000;
    }
    if (restarts > 0) ++after;
    last = t;
  }
  CHECK(view.stop() == 0);
  CHECK(restarts >= 1);
  CHECK(after >= 500);
  CHECK(in_order);
  CHECK_THAT(pass, Catch::StartsWith("pass "));
}
