/// The page server's files (foxglove/web_path.h): the target's lexical rules, the resolution
/// beneath a canonical root (symlinks out, dotfiles, folders, FIFOs, types), and the same over a
/// real socket against a FoxgloveServer: every traversal form refused with 400 or 404 and a
/// fixed body, a secret outside the root never in an answer, the page's files served with their
/// types, HEAD without a body, other methods 405.

#include <catch2/catch.hpp>

#include <sys/stat.h>
#include <unistd.h>

#include <filesystem>
#include <fstream>
#include <string>
#include <utility>
#include <vector>

#include "foxglove/foxglove_server.h"
#include "foxglove/web_path.h"
#include "tests/foxglove/http_test_client.h"
#include "tests/support/scratch.h"

using namespace nimble::foxglove;
using namespace nimble::foxglove::test;
namespace fs = std::filesystem;

namespace {

/// A web root in a temporary folder: the page's files, a dotfile and a dot-folder, symlinks that
/// lead out (absolute, relative, a folder, "/") and one that stays in, a FIFO, a file of an
/// unknown type; next to it, outside, files holding `token`.
struct WebRoot {
  WebRoot() {
    base = nimble::test::scratch_dir("web_path");
    root = base / "root";
    fs::create_directories(root / "sub");
    fs::create_directories(root / ".git");
    fs::create_directories(base / "outside");
    token = "SECRET-" + std::to_string(::getpid());
    write(base / "secret.html", token);
    write(base / "outside" / "secret.txt", token);
    write(root / "index.html", "<html>page</html>");
    write(root / "app.js", "console.log(1);");
    write(root / "style.css", "body{}");
    write(root / "data.json", "{}");
    write(root / "sub" / "page.html", "<p>sub</p>");
    write(root / "notes.bin", token);
    write(root / ".secret", token);
    write(root / ".git" / "config", token);
    fs::create_symlink(base / "secret.html", root / "out.html");
    fs::create_symlink("../secret.html", root / "rel_out.html");
    fs::create_symlink(base / "outside", root / "outdir");
    fs::create_symlink("/", root / "fsroot");
    fs::create_symlink(".secret", root / "to_dot.txt");
    fs::create_symlink("index.html", root / "in.html");
    fs::create_symlink(root, base / "root_link");
    REQUIRE(::mkfifo((root / "pipe.js").c_str(), 0600) == 0);
    canonical_root = fs::canonical(root);
  }
  ~WebRoot() { fs::remove_all(base); }  // does not follow the symlinks
  static void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

  fs::path base, root, canonical_root;
  std::string token;
};

/// Targets the lexical rules refuse (400): absolute and other non-origin forms, dot-segments in
/// any spelling and encoding, encoded separators, backslashes, double encoding, overlong UTF-8,
/// NUL and control characters, bad escapes, bytes outside a path, too long.
const std::vector<std::string>& malformed_targets() {
  static const std::vector<std::string> t = {"//etc/passwd",
                                             "///etc/passwd",
                                             "/sub//page.html",
                                             "",
                                             "*",
                                             "http://127.0.0.1/etc/passwd",
                                             "http://127.0.0.1//etc/passwd",
                                             "127.0.0.1:80",
                                             "etc/passwd",
                                             "/..",
                                             "/.",
                                             "/./index.html",
                                             "/../secret.html",
                                             "/sub/../../secret.html",
                                             "/%2e%2e/secret.html",
                                             "/%2E%2e/secret.html",
                                             "/.%2e/secret.html",
                                             "/%2e./secret.html",
                                             "/sub/%2e%2e/%2e%2e/secret.html",
                                             "/..%2fsecret.html",
                                             "/%2e%2e%2fsecret.html",
                                             "/%2fetc%2fpasswd",
                                             "/..%5csecret.html",
                                             "/..\\secret.html",
                                             "/%252e%252e/secret.html",
                                             "/%25%32%65%25%32%65/secret.html",
                                             "/%c0%ae%c0%ae/secret.html",
                                             "/%c0%af",
                                             "/%e0%80%ae%e0%80%ae/secret.html",
                                             "/index.html%00.png",
                                             "/%00",
                                             "/x%0a",
                                             "/x%0d%0aSet-Cookie:%20a",
                                             "/%7f",
                                             "/%",
                                             "/%2",
                                             "/%zz",
                                             "/%%32%65",
                                             "/a#b",
                                             "/<script>",
                                             "/\xc3\xa9.html",
                                             std::string("/index.html\0.js", 15),
                                             "/\x01",
                                             "/index.html%2f",
                                             "/sub/.x/..",
                                             "/" + std::string(3000, 'a')};
  return t;
}

/// Well-formed targets of nothing served (404): dotfiles and dot-folders, symlinks leading out,
/// a symlink to a dotfile, a FIFO, folders, unknown types, missing files.
const std::vector<std::string>& not_served_targets() {
  static const std::vector<std::string> t = {"/.secret",
                                             "/.git/config",
                                             "/%2egit/config",
                                             "/sub/.hidden.html",
                                             "/out.html",
                                             "/rel_out.html",
                                             "/outdir/secret.txt",
                                             "/fsroot/etc/passwd",
                                             "/fsroot/etc/hostname",
                                             "/to_dot.txt",
                                             "/pipe.js",
                                             "/sub",
                                             "/sub/",
                                             "/outdir",
                                             "/notes.bin",
                                             "/missing.css",
                                             "/index.html/",
                                             "/%3cscript%3e.html",
                                             "/index.HTML"};
  return t;
}

}  // namespace

TEST_CASE("web path: the target's lexical rules (400 malformed, 404 dotfiles, the query stripped)",
          "[foxglove][web][resource]") {
  const std::vector<std::pair<std::string, std::string>> good = {
      {"/", "index.html"},         {"/?ws=ws://127.0.0.1:8765&x=../../etc/passwd", "index.html"},
      {"/sub/", "sub/index.html"}, {"/sub/p%61ge.html", "sub/page.html"},
      {"/a%20b.html", "a b.html"}, {"/app.js?v=1", "app.js"}};
  for (const auto& [target, relative] : good) {
    INFO(target);
    const WebPath w = parse_web_target(target);
    CHECK(w.status == 200);
    CHECK(w.file == fs::path(relative));
    CHECK(w.file.is_relative());
  }
  for (const std::string& target : malformed_targets()) {
    INFO(target);
    CHECK(parse_web_target(target).status == 400);
  }
  for (const char* target : {"/.secret", "/.git/config", "/%2egit/config", "/sub/.hidden.html", "/...x"}) {
    INFO(target);
    CHECK(parse_web_target(target).status == 404);
  }

  CHECK(std::string(web_content_type("index.html")) == "text/html; charset=utf-8");
  CHECK(std::string(web_content_type("dashboard.js")) == "text/javascript; charset=utf-8");
  CHECK(std::string(web_content_type("uPlot.min.css")) == "text/css; charset=utf-8");
  for (const char* name : {"notes.bin", "x.HTML", ".html", "Makefile", "a.tar.gz", "x.php"}) {
    INFO(name);
    CHECK(web_content_type(name) == nullptr);
  }
  CHECK(web_path_beneath("/srv/root", "/srv/root/a/b.js"));
  CHECK(web_path_beneath("/srv/root/", "/srv/root/a"));
  CHECK_FALSE(web_path_beneath("/srv/root", "/srv/root"));
  CHECK_FALSE(web_path_beneath("/srv/root", "/srv/rootx/a"));
  CHECK_FALSE(web_path_beneath("/srv/root", "/srv"));
  CHECK_FALSE(web_path_beneath("/srv/root", "/srv/root/../x"));
  CHECK_FALSE(web_path_beneath("/srv/root", "/srv/root/.git/config"));
}

TEST_CASE("web path: resolved beneath the canonical root, symlinks out, dotfiles, folders and FIFOs are 404",
          "[foxglove][web][resource]") {
  WebRoot w;
  const WebPath index = resolve_web_path(w.canonical_root, "/");
  CHECK(index.status == 200);
  CHECK(index.file == w.canonical_root / "index.html");
  CHECK(std::string(index.content_type) == "text/html; charset=utf-8");
  const WebPath in = resolve_web_path(w.canonical_root, "/in.html");  // a symlink that stays inside
  CHECK(in.status == 200);
  CHECK(in.file == w.canonical_root / "index.html");
  const WebPath js = resolve_web_path(w.canonical_root, "/app.js");
  CHECK(js.status == 200);
  CHECK(std::string(js.content_type) == "text/javascript; charset=utf-8");
  CHECK(resolve_web_path(w.canonical_root, "/sub/page.html").status == 200);
  for (const std::string& target : not_served_targets()) {
    INFO(target);
    CHECK(resolve_web_path(w.canonical_root, target).status == 404);
  }
  for (const std::string& target : malformed_targets()) {
    INFO(target);
    CHECK(resolve_web_path(w.canonical_root, target).status == 400);
  }
  CHECK(resolve_web_path("relative/root", "/index.html").status == 404);  // not a canonical root
}

TEST_CASE("server: the page server over a socket refuses every traversal form, serves the page's files",
          "[foxglove][server][web][resource]") {
  WebRoot w;
  ServerOptions o;
  o.port = 0;
  o.web_root = (w.base / "root_link").string();  // the root through a symlink: served canonically
  FoxgloveServer server(o);
  server.start();
  const uint16_t port = server.port();

  std::vector<std::string> refused = malformed_targets();
  refused.insert(refused.end(), not_served_targets().begin(), not_served_targets().end());
  refused.push_back("/" + w.base.string() + "/secret.html");  // "//tmp/.../secret.html"
  refused.push_back("/a b");                                  // not a request line the parser takes
  for (const std::string& target : refused) {
    for (const char* method : {"GET", "HEAD"}) {
      INFO(method << " " << target);
      const HttpAnswer a = http_request(port, method, target);
      CHECK((a.status == 400 || a.status == 404));
      // A fixed body, never the target; none for HEAD, unless the parser refused the request line
      // before its method was known.
      if (method == std::string("GET"))
        CHECK((a.body == "bad request\n" || a.body == "not found\n"));
      else
        CHECK((a.body.empty() || (a.status == 400 && a.body == "bad request\n")));
      CHECK(a.raw.find(w.token) == std::string::npos);
      CHECK(a.raw.find("root:x:0:0") == std::string::npos);
      CHECK(a.raw.find("Set-Cookie") == std::string::npos);
    }
  }
  // Raw bytes the request line may not hold at all: a 400 from the parser.
  for (const std::string& line : {std::string("GET /index.html\0 HTTP/1.1", 25), std::string("GET /\x7f HTTP/1.1"),
                                  std::string("GET /\r HTTP/1.1"), std::string("GARBAGE")}) {
    INFO(line);
    const HttpAnswer a = http_exchange(port, line + "\r\nHost: 127.0.0.1\r\n\r\n");
    CHECK(a.status == 400);
    CHECK(a.raw.find(w.token) == std::string::npos);
  }

  const std::vector<std::pair<std::string, std::string>> served = {
      {"/", "text/html; charset=utf-8"},
      {"/?ws=ws://127.0.0.1:8765", "text/html; charset=utf-8"},
      {"/in.html", "text/html; charset=utf-8"},
      {"/app.js", "text/javascript; charset=utf-8"},
      {"/style.css", "text/css; charset=utf-8"},
      {"/data.json", "application/json"},
      {"/sub/p%61ge.html", "text/html; charset=utf-8"}};
  for (const auto& [target, type] : served) {
    INFO(target);
    const HttpAnswer a = http_request(port, "GET", target);
    CHECK(a.status == 200);
    CHECK(a.header("Content-Type") == type);
    CHECK(a.header("X-Content-Type-Options") == "nosniff");
  }
  CHECK(http_request(port, "GET", "/").body == "<html>page</html>");
  const HttpAnswer head = http_request(port, "HEAD", "/app.js");
  CHECK(head.status == 200);
  CHECK(head.header("Content-Length") == "15");
  CHECK(head.body.empty());
  for (const char* method : {"POST", "PUT", "DELETE", "OPTIONS", "TRACE"}) {
    INFO(method);
    const HttpAnswer a = http_request(port, method, "/index.html");
    CHECK(a.status == 405);
    CHECK(a.header("Allow") == "GET, HEAD");
  }
  CHECK(server.loopback());
}

TEST_CASE("server: loopback() is false for an address other machines may reach", "[foxglove][server][resource]") {
  ServerOptions o;
  o.port = 0;
  CHECK(FoxgloveServer(o).loopback());
  o.host = "0.0.0.0";
  CHECK_FALSE(FoxgloveServer(o).loopback());  // bound, never started: nothing is accepted
}
