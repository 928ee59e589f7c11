#include "foxglove/web_path.h"

#include <string>
#include <system_error>

namespace nimble::foxglove {

namespace fs = std::filesystem;

namespace {

/// A byte RFC 3986 allows in a path as it is (unreserved, sub-delims, ':', '@'), or '%'.
bool path_char(unsigned char c) {
  if ((c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9')) return true;
  switch (c) {
    case '-':
    case '.':
    case '_':
    case '~':  // unreserved
    case '!':
    case '$':
    case '&':
    case '\'':
    case '(':
    case ')':
    case '*':
    case '+':  // sub-delims
    case ',':
    case ';':
    case '=':
    case ':':
    case '@':
    case '%': return true;
    default: return false;
  }
}

int hex_digit(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

WebPath refusal(int status) {
  WebPath w;
  w.status = status;
  return w;
}

struct ContentType {
  const char* extension;
  const char* type;
};

constexpr ContentType kContentTypes[] = {
    {".html", "text/html; charset=utf-8"},
    {".htm", "text/html; charset=utf-8"},
    {".js", "text/javascript; charset=utf-8"},
    {".mjs", "text/javascript; charset=utf-8"},
    {".css", "text/css; charset=utf-8"},
    {".json", "application/json"},
    {".map", "application/json"},
    {".svg", "image/svg+xml"},
    {".png", "image/png"},
    {".ico", "image/x-icon"},
    {".txt", "text/plain; charset=utf-8"},
    {".woff2", "font/woff2"},
};

}  // namespace

const char* web_content_type(std::string_view file_name) {
  const std::size_t dot = file_name.rfind('.');
  if (dot == std::string_view::npos || dot == 0) return nullptr;  // no extension, or a dotfile
  const std::string_view extension = file_name.substr(dot);
  for (const ContentType& t : kContentTypes) {
    if (extension == t.extension) return t.type;
  }
  return nullptr;
}

WebPath parse_web_target(std::string_view target) {
  if (target.size() > kMaxWebTarget) return refusal(400);
  const std::string_view path = target.substr(0, target.find('?'));
  if (path.empty() || path[0] != '/') return refusal(400);  // absolute-form, authority-form, "*"
  std::string relative;
  bool hidden = false;
  std::size_t at = 1;
  while (true) {
    const std::size_t slash = path.find('/', at);
    const std::size_t end = slash == std::string_view::npos ? path.size() : slash;
    const bool last = end == path.size();
    const std::string_view raw = path.substr(at, end - at);
    if (raw.empty()) {
      if (!last) return refusal(400);  // "//etc/passwd", "/a//b"
      relative += "index.html";        // "/" or "/dir/": never a listing
      break;
    }
    std::string segment;
    for (std::size_t i = 0; i < raw.size(); ++i) {
      unsigned char c = static_cast<unsigned char>(raw[i]);
      if (!path_char(c)) return refusal(400);
      if (c == '%') {
        if (i + 2 >= raw.size()) return refusal(400);
        const int high = hex_digit(raw[i + 1]), low = hex_digit(raw[i + 2]);
        if (high < 0 || low < 0) return refusal(400);
        c = static_cast<unsigned char>(high * 16 + low);
        i += 2;
        // Control characters and NUL, bytes over 0x7e (overlong UTF-8 as %c0%ae too), an encoded
        // separator, and a second level of encoding.
        if (c < 0x20 || c >= 0x7f || c == '/' || c == '\\' || c == '%') return refusal(400);
      }
      segment += static_cast<char>(c);
    }
    if (segment == "." || segment == "..") return refusal(400);
    if (segment[0] == '.') hidden = true;  // decided after the whole target is checked for 400
    relative += segment;
    if (last) break;
    relative += '/';
    at = end + 1;
  }
  if (hidden) return refusal(404);
  WebPath w;
  w.status = 200;
  w.file = relative;
  return w;
}

bool web_path_beneath(const fs::path& canonical_root, const fs::path& path) {
  auto p = path.begin();
  for (const fs::path& r : canonical_root) {
    if (r.empty()) continue;  // a trailing '/'
    if (p == path.end() || *p != r) return false;
    ++p;
  }
  if (p == path.end()) return false;  // the root itself
  for (; p != path.end(); ++p) {
    const std::string& name = p->native();
    if (name.empty() || name[0] == '.') return false;
  }
  return true;
}

WebPath resolve_web_path(const fs::path& canonical_root, std::string_view target) {
  WebPath w = parse_web_target(target);
  if (w.status != 200) return w;
  if (!canonical_root.is_absolute()) return refusal(404);
  std::error_code ec;
  const fs::path file = fs::canonical(canonical_root / w.file, ec);
  if (ec || !web_path_beneath(canonical_root, file)) return refusal(404);
  const char* type = web_content_type(file.filename().native());
  if (type == nullptr) return refusal(404);
  const fs::file_status status = fs::status(file, ec);
  if (ec || !fs::is_regular_file(status)) return refusal(404);
  w.file = file;
  w.content_type = type;
  return w;
}

}  // namespace nimble::foxglove
