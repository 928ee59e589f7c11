#pragma once
/// A plain HTTP client for the page server's tests: writes a request's bytes exactly as given
/// (any target, any byte) on a POSIX socket and reads everything the server sends until it
/// closes, bounded in time.

#include <arpa/inet.h>
#include <netinet/in.h>
#include <sys/socket.h>
#include <sys/time.h>
#include <unistd.h>

#include <cctype>
#include <cstdint>
#include <string>

namespace nimble::foxglove::test {

/// An HTTP answer as it came: status 0 if there was none.
struct HttpAnswer {
  int status = 0;
  std::string raw;      ///< every byte received
  std::string headers;  ///< the status line and the header fields
  std::string body;     ///< every byte after the header's blank line

  /// The value of header field `name` (any case), "" if absent.
  std::string header(const std::string& name) const {
    std::size_t at = headers.find("\r\n");
    while (at != std::string::npos && at + 2 < headers.size()) {
      const std::size_t end = headers.find("\r\n", at + 2);
      const std::string line = headers.substr(at + 2, end == std::string::npos ? std::string::npos : end - at - 2);
      const std::size_t colon = line.find(':');
      if (colon == name.size()) {
        bool same = true;
        for (std::size_t i = 0; i < colon; ++i) {
          same = same &&
                 std::tolower(static_cast<unsigned char>(line[i])) == std::tolower(static_cast<unsigned char>(name[i]));
        }
        if (same) return line.substr(line.find_first_not_of(' ', colon + 1));
      }
      at = end;
    }
    return "";
  }
};

/// Sends `request` (bytes as they are) to 127.0.0.1:`port` and reads until the server closes or
/// `timeout_s` passes without a byte.
inline HttpAnswer http_exchange(uint16_t port, const std::string& request, double timeout_s = 3.0) {
  HttpAnswer a;
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return a;
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(timeout_s);
  tv.tv_usec = static_cast<suseconds_t>((timeout_s - static_cast<double>(tv.tv_sec)) * 1e6);
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(port);
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) {
    std::size_t sent = 0;
    while (sent < request.size()) {
      const ssize_t n = ::send(fd, request.data() + sent, request.size() - sent, MSG_NOSIGNAL);
      if (n <= 0) break;
      sent += static_cast<std::size_t>(n);
    }
    char buffer[4096];
    ssize_t n = 0;
    while ((n = ::recv(fd, buffer, sizeof buffer, 0)) > 0) a.raw.append(buffer, static_cast<std::size_t>(n));
  }
  ::close(fd);
  const std::size_t blank = a.raw.find("\r\n\r\n");
  a.headers = a.raw.substr(0, blank);
  if (blank != std::string::npos) a.body = a.raw.substr(blank + 4);
  if (a.raw.compare(0, 9, "HTTP/1.1 ") == 0 && a.raw.size() >= 12) {
    for (std::size_t i = 9; i < 12 && std::isdigit(static_cast<unsigned char>(a.raw[i])); ++i) {
      a.status = a.status * 10 + (a.raw[i] - '0');
    }
  }
  return a;
}

/// `METHOD TARGET HTTP/1.1` with a Host field, `target` as it is.
inline HttpAnswer http_request(uint16_t port, const std::string& method, const std::string& target) {
  return http_exchange(port, method + " " + target + " HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Length: 0\r\n\r\n");
}

}  // namespace nimble::foxglove::test
