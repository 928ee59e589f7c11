/// The plain HTTP side of FoxgloveServer: one request per connection, an upgrade handed to a
/// WebSocket session, anything else answered with a file of the web root (web_path.h's rules)
/// or why not.

#include <fcntl.h>
#include <linux/openat2.h>
#include <sys/stat.h>
#include <sys/syscall.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <utility>

#include "core/input_file.h"
#include "foxglove/protocol.h"
#include "foxglove/server_impl.h"
#include "foxglove/web_path.h"

namespace nimble::foxglove {

namespace {

constexpr const char* kTextPlain = "text/plain; charset=utf-8";

/// Reads `file` (canonical, beneath the canonical `root`, as resolve_web_path() gives it) if it is
/// a regular file. It is opened from the root's descriptor with openat2(RESOLVE_BENEATH |
/// RESOLVE_NO_SYMLINKS): a component changed into a symlink, or anything leading out of the
/// root, since the path was resolved is refused. Where the kernel has no openat2 (ENOSYS, or a
/// seccomp filter's EPERM) it is opened by its path with O_NOFOLLOW. O_NONBLOCK: a FIFO put there
/// does not hold up the I/O thread (it is not a regular file and is refused); a file above the
/// bound of a web root's file (core/input_file.h) is refused too.
bool read_web_file(const std::filesystem::path& root, const std::filesystem::path& file, std::string* body) {
  const int flags = O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC | O_NOCTTY;
  const int root_fd = ::open(root.c_str(), O_PATH | O_DIRECTORY | O_NOFOLLOW | O_CLOEXEC);
  if (root_fd < 0) return false;
  open_how how{};
  how.flags = static_cast<uint64_t>(flags);
  how.resolve = RESOLVE_BENEATH | RESOLVE_NO_SYMLINKS | RESOLVE_NO_MAGICLINKS;
  const std::filesystem::path relative = file.lexically_relative(root);
  int fd = static_cast<int>(::syscall(SYS_openat2, root_fd, relative.c_str(), &how, sizeof how));
  const int open_errno = errno;
  ::close(root_fd);
  if (fd < 0 && (open_errno == ENOSYS || open_errno == EPERM)) fd = ::open(file.c_str(), flags);
  if (fd < 0) return false;
  bool ok = true;
  try {
    *body = read_input_descriptor(fd, file.string(), InputKind::kWebFile);  // a regular file within its bound
  } catch (const InputFileError&) {
    body->clear();
    ok = false;
  }
  ::close(fd);
  return ok;
}

/// A connection before it is a WebSocket: reads one HTTP request; an upgrade becomes a
/// WsSession, anything else is answered (a static file, or why not) and closed.
class HttpConnection : public std::enable_shared_from_this<HttpConnection> {
 public:
  HttpConnection(FoxgloveServer::Impl* server, tcp::socket socket) : server_(server), stream_(std::move(socket)) {}

  void start() {
    parser_.emplace();
    parser_->header_limit(16 * 1024);
    parser_->body_limit(16 * 1024);
    stream_.expires_after(std::chrono::seconds(30));
    http::async_read(stream_, buffer_, *parser_,
                     [self = shared_from_this()](beast::error_code ec, std::size_t) { self->on_read(ec); });
  }

 private:
  void on_read(beast::error_code ec) {
    if (ec) {
      // Bytes that are not an HTTP request (a bad request line or target, headers over the
      // limit) get a 400; a connection closed or timed out before a whole request, nothing.
      if (ec.category() == make_error_code(http::error::bad_target).category() && ec != http::error::end_of_stream &&
          ec != http::error::partial_message && ec != http::error::need_more) {
        server_->http_requests.fetch_add(1);
        respond(11, false, http::status::bad_request, kTextPlain, "bad request\n");
      }
      return;
    }
    http::request<http::string_body> req = parser_->release();
    if (websocket::is_upgrade(req)) {
      const std::string sub = choose_subprotocol(std::string(req[http::field::sec_websocket_protocol]));
      if (sub.empty()) {
        server_->handshakes_refused.fetch_add(1);
        respond(req, http::status::bad_request, kTextPlain,
                std::string("This Foxglove WebSocket server speaks the subprotocol ") + kSubprotocolV1 + " (or " +
                    kSubprotocolSdk + "); the handshake offered neither.\n");
        return;
      }
      uint64_t id = 0;
      {
        std::lock_guard<std::mutex> lock(server_->sessions_mu);
        id = server_->next_client_id++;
      }
      start_websocket(server_, std::move(stream_), sub, id, std::move(req));
      return;
    }
    server_->http_requests.fetch_add(1);
    serve_file(req);
  }

  /// A file of the web root by the rules of web_path.h; the answers never repeat the request.
  void serve_file(const http::request<http::string_body>& req) {
    if (req.method() != http::verb::get && req.method() != http::verb::head) {
      respond(req, http::status::method_not_allowed, kTextPlain, "only GET and HEAD\n");
      return;
    }
    if (server_->web_root.empty()) {
      respond(req, http::status::not_found, kTextPlain,
              "This is a Foxglove WebSocket server: in Foxglove or Lichtblick, Open connection -> Foxglove "
              "WebSocket -> ws://" +
                  endpoint_text(stream_.socket().local_endpoint(ignored_)) + "\n");
      return;
    }
    const auto target = req.target();
    const WebPath w = resolve_web_path(server_->web_root, std::string_view(target.data(), target.size()));
    if (w.status == 400) {
      respond(req, http::status::bad_request, kTextPlain, "bad request\n");
      return;
    }
    std::string body;
    if (w.status != 200 || !read_web_file(server_->web_root, w.file, &body)) {
      respond(req, http::status::not_found, kTextPlain, "not found\n");
      return;
    }
    respond(req, http::status::ok, w.content_type, std::move(body));
  }

  void respond(const http::request<http::string_body>& req, http::status status, const char* type, std::string body) {
    respond(req.version(), req.method() == http::verb::head, status, type, std::move(body));
  }

  /// Answers with `body` (only its length for a HEAD request) and closes.
  void respond(unsigned version, bool head, http::status status, const char* type, std::string body) {
    auto res = std::make_shared<http::response<http::string_body>>(status, version);
    res->set(http::field::server, "nimble_rig foxglove");
    res->set(http::field::content_type, type);
    res->set(http::field::cache_control, "no-store");
    res->set("X-Content-Type-Options", "nosniff");
    if (status == http::status::method_not_allowed) res->set(http::field::allow, "GET, HEAD");
    res->keep_alive(false);
    res->body() = std::move(body);
    res->prepare_payload();
    if (head) res->body().clear();
    http::async_write(stream_, *res, [self = shared_from_this(), res](beast::error_code, std::size_t) {
      beast::error_code ignored;
      self->stream_.socket().shutdown(tcp::socket::shutdown_send, ignored);
    });
  }

  FoxgloveServer::Impl* server_;
  beast::tcp_stream stream_;
  beast::flat_buffer buffer_;
  std::optional<http::request_parser<http::string_body>> parser_;
  beast::error_code ignored_;
};

}  // namespace

void start_http_connection(FoxgloveServer::Impl* server, tcp::socket socket) {
  std::make_shared<HttpConnection>(server, std::move(socket))->start();
}

}  // namespace nimble::foxglove
