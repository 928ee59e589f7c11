#include "campaign/result_files.h"

#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/output_file.h"

namespace nimble::campaign {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

bool key_ok(const std::string& key) {
  if (key.empty() || key[0] == '.') return false;
  for (const char c : key) {
    const bool ok = (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' ||
                    c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

Json read_manifest(const std::string& file) {
  std::ifstream in(file);
  if (!in) throw std::runtime_error("cannot read " + file);
  try {
    return Json::parse(in);
  } catch (const std::exception& e) {
    throw std::runtime_error(file + " is not a campaign manifest (" + e.what() + ")");
  }
}

}  // namespace

std::string ResultFiles::file(const std::string& key) const {
  if (!key_ok(key)) throw std::invalid_argument("result key '" + key + "' holds a character other than [A-Za-z0-9._-]");
  return runs_dir() + "/" + key + ".json";
}

bool ResultFiles::has(const std::string& key) const {
  std::error_code ec;
  return fs::is_regular_file(file(key), ec);
}

std::optional<std::string> ResultFiles::read(const std::string& key) const {
  const std::string f = file(key);
  std::error_code ec;
  if (!fs::exists(f, ec)) return std::nullopt;
  std::ifstream in(f, std::ios::binary);
  std::ostringstream text;
  text << in.rdbuf();
  if (!in) throw std::runtime_error("cannot read the result file " + f);
  std::string s = text.str();
  if (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

void ResultFiles::write(const std::string& key, const std::string& text) const { write_file(file(key), text + "\n"); }

void ResultFiles::remove_partial() const {
  std::error_code ec;
  const std::size_t n = std::strlen(kPartialSuffix);
  for (const auto& e : fs::directory_iterator(runs_dir(), ec)) {
    const std::string name = e.path().filename().string();
    if (name.size() > n && name.compare(name.size() - n, std::string::npos, kPartialSuffix) == 0) {
      fs::remove(e.path(), ec);
    }
  }
}

ResultFiles open_result_dir(const std::string& dir, const std::string& manifest) {
  const Json want = Json::parse(manifest);
  ResultFiles files(fs::absolute(dir).lexically_normal().string());
  if (fs::exists(files.manifest_file())) {
    const Json have = read_manifest(files.manifest_file());
    for (const auto& [key, value] : want.items()) {
      const auto it = have.find(key);
      if (it == have.end() || *it != value) {
        throw std::runtime_error(files.dir() + " holds another campaign: its " + key + " is " +
                                 (it == have.end() ? std::string("missing") : it->dump()) + ", this one's " +
                                 value.dump() + " (a new directory, or the same options, finishes it)");
      }
    }
    for (const auto& [key, value] : have.items()) {
      if (!want.contains(key)) {
        throw std::runtime_error(files.dir() + " holds another campaign: it has " + key + " = " + value.dump() +
                                 ", which this one does not");
      }
    }
  } else {
    std::error_code ec;
    if (fs::exists(files.dir(), ec) && !fs::is_empty(files.dir(), ec)) {
      throw std::runtime_error(files.dir() + " is not empty and holds no campaign (no campaign.json)");
    }
    fs::create_directories(files.runs_dir());
    write_file(files.manifest_file(), want.dump(2) + "\n");
  }
  fs::create_directories(files.runs_dir());
  files.remove_partial();
  return files;
}

std::vector<std::string> run_kept(const KeptItems& items, int jobs, const PoolWork& pool, const ResultFiles* files) {
  const std::size_t n = items.keys.size();
  std::vector<std::string> results(n);
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < n; ++i) {
    const bool again = files == nullptr || (items.redo && items.redo(i));
    const std::optional<std::string> kept = again ? std::nullopt : files->read(items.keys[i]);
    if (kept) {
      results[i] = *kept;
    } else {
      todo.push_back(i);
    }
  }
  const std::size_t read = n - todo.size();
  PoolWork mapped;
  mapped.work = [&](std::size_t k) { return pool.work(todo[k]); };
  mapped.died = [&](std::size_t k, const std::string& how) { return pool.died(todo[k], how); };
  if (pool.started) mapped.started = [&](std::size_t k) { pool.started(todo[k]); };
  mapped.finished = [&](std::size_t k, const std::string& result, std::size_t done) {
    if (files != nullptr && (!items.keep || items.keep(result))) files->write(items.keys[todo[k]], result);
    if (pool.finished) pool.finished(todo[k], result, read + done);
  };
  const std::vector<std::string> done = run_in_workers(todo.size(), jobs, mapped);
  for (std::size_t k = 0; k < todo.size(); ++k) results[todo[k]] = done[k];
  return results;
}

}  // namespace nimble::campaign
