// Fuzz target: the request target of an HTTP GET to the page server (foxglove/web_path.h), the
// input's bytes as they are, resolved against a web root in a scratch folder that holds the
// page's files, a dotfile and a dot-folder, symlinks that lead out of it (absolute, relative, a
// folder, "/") and one that stays in, a FIFO, a file of an unknown type; a secret lies next to
// it. Properties: nothing throws; the answer is 200, 400 or 404, and the lexical rules alone give
// the same 400; an accepted target's relative path has no empty, '.'-led or '%'-holding segment
// and no separator but '/'; an accepted file is lexically normal, beneath the canonical root by
// components with no '.'-led component, its own canonical path, a regular file of a known type,
// and not the secret.

#include <sys/stat.h>

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <string>
#include <string_view>

#include "foxglove/web_path.h"
#include "fuzz/fuzz_support.h"

using namespace nimble::foxglove;
using nimble::fuzz::require;
namespace fs = std::filesystem;

namespace {

struct Root {
  fs::path canonical_root, secret;
};

void write(const fs::path& p, const std::string& text) { std::ofstream(p, std::ios::binary) << text; }

const Root& web_root() {
  static const Root r = [] {
    const fs::path base = fs::path(nimble::fuzz::scratch_dir()) / "web";
    const fs::path root = base / "root";
    fs::create_directories(root / "sub");
    fs::create_directories(root / ".git");
    fs::create_directories(base / "outside");
    write(base / "secret.html", "secret");
    write(base / "outside" / "secret.txt", "secret");
    write(root / "index.html", "<html></html>");
    write(root / "app.js", "");
    write(root / "sub" / "page.html", "");
    write(root / "sub" / "index.html", "");
    write(root / "notes.bin", "");
    write(root / ".secret", "");
    write(root / ".git" / "config", "");
    fs::create_symlink(base / "secret.html", root / "out.html");
    fs::create_symlink("../secret.html", root / "rel_out.html");
    fs::create_symlink(base / "outside", root / "outdir");
    fs::create_symlink("/", root / "fsroot");
    fs::create_symlink(".secret", root / "to_dot.txt");
    fs::create_symlink("index.html", root / "in.html");
    ::mkfifo((root / "pipe.js").c_str(), 0600);
    return Root{fs::canonical(root), fs::canonical(base / "secret.html")};
  }();
  return r;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const Root& r = web_root();
  const std::string_view target(reinterpret_cast<const char*>(data), size);

  const WebPath lexical = parse_web_target(target);
  require(lexical.status == 200 || lexical.status == 400 || lexical.status == 404, "a status other than 200/400/404");
  if (lexical.status == 200) {
    const std::string rel = lexical.file.native();
    require(!rel.empty() && rel.front() != '/' && rel.back() != '/', "an empty or absolute relative path: " + rel);
    require(rel.find('\\') == std::string::npos && rel.find('%') == std::string::npos &&
                rel.find('\0') == std::string::npos,
            "a backslash, '%' or NUL in an accepted path: " + rel);
    for (const fs::path& segment : lexical.file) {
      const std::string& s = segment.native();
      require(!s.empty() && s.front() != '.', "an empty or '.'-led segment accepted: " + rel);
      for (const char c : s) {
        require(static_cast<unsigned char>(c) >= 0x20 && static_cast<unsigned char>(c) < 0x7f,
                "a control or non-ASCII byte accepted: " + rel);
      }
    }
  }

  const WebPath w = resolve_web_path(r.canonical_root, target);
  require(w.status == 200 || w.status == 400 || w.status == 404, "a status other than 200/400/404");
  require((w.status == 400) == (lexical.status == 400), "the resolver's 400 differs from the lexical rules'");
  if (lexical.status != 200) require(w.status == lexical.status, "the resolver accepted what the rules refused");
  if (w.status == 200) {
    const std::string file = w.file.native();
    require(w.file.is_absolute() && w.file.lexically_normal() == w.file,
            "an accepted path that is not normal: " + file);
    require(web_path_beneath(r.canonical_root, w.file), "an accepted path not beneath the root: " + file);
    require(w.file.lexically_relative(r.canonical_root).native().rfind("..", 0) != 0,
            "an accepted path that leaves the root lexically: " + file);
    std::error_code ec;
    require(fs::canonical(w.file, ec) == w.file && !ec, "an accepted path that is not canonical: " + file);
    require(fs::is_regular_file(fs::symlink_status(w.file, ec)),
            "an accepted path that is not a regular file: " + file);
    require(w.file != r.secret, "the secret outside the root accepted");
    require(w.content_type != nullptr && web_content_type(w.file.filename().native()) == w.content_type,
            "an accepted file without its type: " + file);
  }
  return 0;
}
