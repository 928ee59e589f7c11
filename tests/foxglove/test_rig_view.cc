/// `rig view`: a log replayed live to a Foxglove client, a damaged log named by its offset,
/// --salvage, bad options, the page server (--web) refusing paths out of its root.

#include <catch2/catch.hpp>

#include <arpa/inet.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

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

using namespace nimble;
using namespace nimble::foxglove;
using namespace nimble::foxglove::test;

namespace {

/// A 2 s hover log flown in process, made once per test program.
const std::string& hover_log() {
  static const std::string log = [] {
    const std::string dir =
        (std::filesystem::temp_directory_path() / ("rig_view_" + std::to_string(::getpid()))).string();
    std::filesystem::create_directories(dir);
    const std::string file = dir + "/hover.lcmlog";
    const auto r = nimble::test::run_rig("run " + std::string(RIG_SOURCE_DIR) + "/rig_configs/hover.yaml" +
                                         " --clock inprocess --set duration_s=2 --no-progress --log " + file);
    REQUIRE(r.exit_code == 0);
    return file;
  }();
  return log;
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
                            "/rig_configs/hover.yaml --clock inprocess --set duration_s=1 --no-progress --foxglove " + busy);
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--foxglove " + busy + ": cannot listen on " + busy));
  ::close(fd);
}

TEST_CASE("rig view: bad options are usage errors", "[foxglove][view]") {
  CHECK(nimble::test::run_rig("view /no/such.lcmlog --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --foxglove 70000 --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view " + hover_log() + " --speed -1 --exit-when-done").exit_code == 2);
  CHECK(nimble::test::run_rig("view --exit-when-done").exit_code == 2);
  const auto r = nimble::test::run_rig("view " + hover_log() + " --web 0 --web-root /no/such/dir --exit-when-done");
  CHECK(r.exit_code == 2);
  CHECK_THAT(r.err, Catch::Contains("--web-root"));
}

TEST_CASE("rig view: a client gets the log's TRUTH at rig time and the replay's end on rig/verdict",
          "[foxglove][view]") {
  const std::string err = hover_log() + ".view.err";
  const pid_t pid = ::fork();
  if (pid == 0) {
    std::freopen(err.c_str(), "w", stderr);
    std::freopen("/dev/null", "w", stdout);
    ::execl(RIG_BIN, RIG_BIN, "view", hover_log().c_str(), "--foxglove", "127.0.0.1:0", "--speed", "0.5", nullptr);
    ::_exit(127);
  }
  int port = 0;
  const std::regex line("live view on ws://127\\.0\\.0\\.1:([0-9]+)");
  REQUIRE(eventually(
      [&] {
        std::smatch m;
        const std::string text = nimble::test::slurp(err);
        if (!std::regex_search(text, m, line)) return false;
        port = std::stoi(m[1]);
        return true;
      },
      10.0));
  TestClient c;
  REQUIRE_FALSE(c.connect(static_cast<uint16_t>(port), kSubprotocolV1));
  c.read_json();
  const json ad = c.read_json();
  uint32_t truth = 0, verdict = 0;
  for (const auto& ch : ad["channels"]) {
    if (ch["topic"] == contract::channels::kTruth) truth = ch["id"];
    if (ch["topic"] == kVerdictTopic) verdict = ch["id"];
  }
  c.send_text(json{{"op", "subscribe"},
                   {"subscriptions", {{{"id", 1}, {"channelId", truth}}, {{"id", 2}, {"channelId", verdict}}}}}
                  .dump());
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
  ::kill(pid, SIGINT);  // it keeps serving after the replay until told
  int status = 0;
  ::waitpid(pid, &status, 0);
  CHECK(WIFEXITED(status));
  CHECK(WEXITSTATUS(status) == 0);
  CHECK(done);
  CHECK_THAT(final_state, Catch::StartsWith("replayed"));
  // Of 2000 at 1 kHz, replayed at half speed (4 s): the client, subscribed within a second or so,
  // gets most of them.
  CHECK(truths > 500);
  CHECK(in_order);
}

TEST_CASE("rig view --web: //etc/passwd and other paths out of the root are refused, a warning off loopback",
          "[foxglove][view][resource]") {
  const std::filesystem::path base =
      std::filesystem::temp_directory_path() / ("rig_view_web_" + std::to_string(::getpid()));
  std::filesystem::remove_all(base);
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
