#pragma once
/// Which file of its web root the page server (FoxgloveServer's plain HTTP GET) serves for a
/// request target, or why none: the whole decision, apart from opening the file.
///
/// The rules (docs/live_view.md, "What the page server serves"):
/// - 400, a malformed target, decided from the target alone: longer than kMaxWebTarget; not a
///   path that starts with '/' (absolute-form "http://host/x", authority-form, "*"); a byte
///   outside RFC 3986's path characters (space, '\\', '#', '"', '<', control characters, bytes
///   over 0x7f, ...); a '%' not followed by two hex digits; a percent-encoded byte that is a
///   control character, over 0x7f (overlong UTF-8 such as %c0%ae included), '/', '\\' or '%'
///   (double encoding, %252e); an empty segment ("//etc/passwd"); a "." or ".." segment, in any
///   spelling ("%2e%2E").
/// - 404, nothing served there (whether it exists is not told): a segment that starts with '.'
///   (dotfiles and dot-directories); a name whose extension is not in the table of
///   web_content_type(); a path that does not exist, is not a regular file, or whose canonical
///   path (symlinks resolved) is not beneath the canonical root or passes through a dot-name.
/// - The query ("?...") is stripped first and ignored. "/" is "index.html", and a path ending
///   in '/' names that folder's "index.html": no folder is ever listed.

#include <cstddef>
#include <filesystem>
#include <string_view>

namespace nimble::foxglove {

/// The longest request target taken (bytes, the query included).
inline constexpr std::size_t kMaxWebTarget = 2048;

/// What a request target comes to.
struct WebPath {
  int status = 404;                    ///< 200: `file` is served; 400: malformed; 404: nothing served there
  std::filesystem::path file;          ///< status 200: see the functions
  const char* content_type = nullptr;  ///< status 200 from resolve_web_path(): web_content_type(file)
};

/// The lexical part of the rules, without the file system: status 200 and `file` the decoded
/// path relative to the root ("index.html" for "/"), or 400 / 404. Never throws but
/// std::bad_alloc.
WebPath parse_web_target(std::string_view target);

/// The whole rule set: status 200 with `file` the canonical path of a regular file beneath
/// `canonical_root` and its content type, or 400 / 404. `canonical_root` must be canonical
/// (std::filesystem::canonical); it reads the file system (symlinks, file types) but opens
/// nothing. Never throws but std::bad_alloc.
WebPath resolve_web_path(const std::filesystem::path& canonical_root, std::string_view target);

/// The content type of a file name by its extension, from a fixed table (.html .htm .js .mjs
/// .css .json .map .svg .png .ico .txt .woff2); nullptr for any other name, which is not
/// served.
const char* web_content_type(std::string_view file_name);

/// Whether `path` is beneath `canonical_root` (a component of its own at least), by components,
/// with no component below the root that starts with '.'.
bool web_path_beneath(const std::filesystem::path& canonical_root, const std::filesystem::path& path);

}  // namespace nimble::foxglove
