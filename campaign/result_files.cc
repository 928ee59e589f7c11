#include "campaign/result_files.h"

#include <unistd.h>

#include <algorithm>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/input_file.h"
#include "core/output_file.h"
#include "core/output_lock.h"

namespace nimble::campaign {

namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// What a manifest records without making the campaign another: when, where, by which process.
constexpr const char* kMadeKey = "made";
/// The key compared first: which command's campaign it is; then its format.
constexpr const char* kCampaignKey = "campaign";
constexpr const char* kFormatKey = "format";
constexpr const char* kReadAgain = "; remove it and the item is done again, or use the directory it came from";

double unix_time_s() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

bool key_ok(const std::string& key) {
  if (key.empty() || key[0] == '.') return false;
  for (const char c : key) {
    const bool ok =
        (c >= 'a' && c <= 'z') || (c >= 'A' && c <= 'Z') || (c >= '0' && c <= '9') || c == '.' || c == '_' || c == '-';
    if (!ok) return false;
  }
  return true;
}

/// A manifest or result file, whole: a regular file within a campaign file's bound
/// (core/input_file.h). @throws InputFileError naming the file and the problem.
std::string slurp(const std::string& file) { return read_input_file(file, InputKind::kCampaign); }

Json parse_manifest(const std::string& file) {
  try {
    Json m = Json::parse(slurp(file));
    if (!m.is_object()) throw std::runtime_error("not a JSON object");
    return m;
  } catch (const std::exception& e) {
    throw std::runtime_error(file + " is not a campaign manifest (" + std::string(e.what()) + ")");
  }
}

/// The identity of a campaign: the digest (FNV-1a, 16 hex digits) of its manifest's bytes as
/// written, "made" and all: two campaigns made apart with the same options are two campaigns.
std::string identity_of(const std::string& manifest_text) {
  uint64_t h = 1469598103934665603ULL;
  for (const unsigned char c : manifest_text) {
    h ^= c;
    h *= 1099511628211ULL;
  }
  char buf[17];
  std::snprintf(buf, sizeof buf, "%016llx", static_cast<unsigned long long>(h));
  return buf;
}

std::string campaign_line(const std::string& identity, const std::string& key) {
  return Json{{kCampaignKey, identity}, {"item", key}}.dump();
}

bool is_partial(const std::string& name) {
  const std::size_t n = std::strlen(kPartialSuffix);
  return name.size() > n && name.compare(name.size() - n, std::string::npos, kPartialSuffix) == 0;
}

/// Why `line` (a result file's first line) is not the campaign line of `key` in campaign
/// `identity`; empty if it is.
std::string line_problem(const std::string& line, const std::string& identity, const std::string& key,
                         const std::string& manifest_file) {
  Json head;
  try {
    head = Json::parse(line);
  } catch (const std::exception&) {
  }
  if (!head.is_object() || !head.contains(kCampaignKey) || !head[kCampaignKey].is_string() || !head.contains("item") ||
      !head["item"].is_string()) {
    return "it does not start with a campaign line (a file of the user's, of another program or of an older rig)";
  }
  const std::string theirs = head[kCampaignKey].get<std::string>();
  if (theirs != identity) {
    return "it is a result of another campaign (campaign " + theirs + "; this one, " + manifest_file + ", is " +
           identity + ")";
  }
  if (head["item"].get<std::string>() != key) {
    return "it holds item " + head["item"].get<std::string>() + ", not " + key;
  }
  return "";
}

/// The first entries of DIR, for a message ("scenario.yaml, runs/, ...").
std::string some_entries(const std::string& dir) {
  std::vector<std::string> names;
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(dir, ec)) {
    names.push_back(e.path().filename().string() + (e.is_directory(ec) ? "/" : ""));
  }
  std::sort(names.begin(), names.end());
  std::string text;
  for (std::size_t k = 0; k < std::min<std::size_t>(names.size(), 4); ++k) text += (k ? ", " : "") + names[k];
  if (names.size() > 4) text += ", ... (" + std::to_string(names.size()) + " entries)";
  return text;
}

/// Refuses unless `have` (DIR's manifest) is `want`, apart from what it records: names the first
/// key that differs, the campaign key first.
void check_same_campaign(const std::string& dir, const Json& want, const Json& have) {
  std::vector<std::string> keys = {kCampaignKey, kFormatKey};
  for (const auto& [key, value] : want.items()) {
    if (key != kCampaignKey && key != kFormatKey && key != kMadeKey) keys.push_back(key);
  }
  for (const std::string& key : keys) {
    const auto it = have.find(key);
    if (it == have.end() || *it != want[key]) {
      throw std::runtime_error(dir + " holds another campaign: its " + key + " is " +
                               (it == have.end() ? std::string("missing") : it->dump()) + ", this one's " +
                               want[key].dump() +
                               (key == kFormatKey ? " (a campaign of another rig: finish it with the rig that made it)"
                                                  : " (a new directory, or the same options, finishes it)"));
    }
  }
  for (const auto& [key, value] : have.items()) {
    if (key != kMadeKey && !want.contains(key)) {
      throw std::runtime_error(dir + " holds another campaign: it has " + key + " = " + value.dump() +
                               ", which this one does not");
    }
  }
}

}  // namespace

void to_json(Json& j, const Manifest& m) {
  j = Json::object();
  j[kCampaignKey] = m.campaign;
  j[kFormatKey] = kManifestFormat;
  for (const auto& [key, value] : m.fields.items()) {
    if (key == kCampaignKey || key == kFormatKey || key == kMadeKey) {
      throw std::invalid_argument("a campaign's key '" + key + "' is one the manifest keeps for itself");
    }
    j[key] = value;
  }
  if (!m.made.is_null()) j[kMadeKey] = m.made;
}

void from_json(const Json& j, Manifest& m) {
  if (!j.is_object()) throw std::runtime_error("not a JSON object");
  if (!j.contains(kCampaignKey) || !j[kCampaignKey].is_string()) throw std::runtime_error("no campaign");
  const Json format = j.value(kFormatKey, Json());
  if (format != kManifestFormat) {
    throw std::runtime_error("format " + (format.is_null() ? std::string("missing") : format.dump()) +
                             ", this rig reads \"" + kManifestFormat +
                             "\" (a campaign of another rig: finish it with the rig that made it)");
  }
  m.campaign = j[kCampaignKey].get<std::string>();
  m.fields = Json::object();
  for (const auto& [key, value] : j.items()) {
    if (key != kCampaignKey && key != kFormatKey && key != kMadeKey) m.fields[key] = value;
  }
  m.made = j.value(kMadeKey, Json());
  if (!m.made.is_null() && !(m.made.is_object() && m.made.contains("unix_s") && m.made["unix_s"].is_number())) {
    throw std::runtime_error("its made has no unix_s");
  }
}

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
  if (!fs::is_regular_file(f, ec)) throw ForeignResult(f + " is not a result file of a campaign: not a regular file");
  std::string s;
  try {
    s = slurp(f);
  } catch (const std::exception& e) {
    throw std::runtime_error("cannot read the result file " + f + ": " + e.what());
  }
  const std::size_t eol = s.find('\n');
  if (eol == std::string::npos) throw std::runtime_error("the result file " + f + " ends within its campaign line");
  const std::string problem = line_problem(s.substr(0, eol), identity_, key, manifest_file());
  if (!problem.empty()) throw ForeignResult(f + " is not a result of this campaign: " + problem + kReadAgain);
  s.erase(0, eol + 1);
  if (!s.empty() && s.back() == '\n') s.pop_back();
  return s;
}

void ResultFiles::write(const std::string& key, const std::string& text) const {
  write_file(file(key), campaign_line(identity_, key) + "\n" + text + "\n");
}

void ResultFiles::remove_partial() const {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(runs_dir(), ec)) {
    if (is_partial(e.path().filename().string())) fs::remove(e.path(), ec);
  }
}

void ResultFiles::check_all() const {
  std::error_code ec;
  for (const auto& e : fs::directory_iterator(runs_dir(), ec)) {
    const std::string name = e.path().filename().string(), f = e.path().string();
    if (is_partial(name)) continue;
    const std::string key = name.size() > 5 ? name.substr(0, name.size() - 5) : "";
    if (name.compare(key.size(), std::string::npos, ".json") != 0 || !key_ok(key) || !e.is_regular_file(ec)) {
      throw ForeignResult(f + " is not a result file of a campaign (a result file is runs/<item>.json)" + kReadAgain);
    }
    check_input_file(f, InputKind::kCampaign);  // its first line is read: within a campaign file's bound
    std::ifstream in(f, std::ios::binary);
    std::string line;
    if (!std::getline(in, line) || in.eof()) continue;  // cut short: read() names it as damaged
    const std::string problem = line_problem(line, identity_, key, manifest_file());
    if (!problem.empty()) throw ForeignResult(f + " is not a result of this campaign: " + problem + kReadAgain);
  }
}

Manifest read_manifest(const std::string& dir) {
  const std::string file = ResultFiles(fs::absolute(dir).lexically_normal().string(), "").manifest_file();
  std::error_code ec;
  if (!fs::exists(file, ec))
    throw std::runtime_error("no campaign in " + fs::path(file).parent_path().string() + " (no " + file + ")");
  const Json m = parse_manifest(file);
  try {
    return m.get<Manifest>();
  } catch (const std::exception& e) {
    throw std::runtime_error(file + " is not a campaign manifest of this rig: " + e.what());
  }
}

ResultFiles attach_result_dir(const std::string& dir) {
  const std::string abs = fs::absolute(dir).lexically_normal().string();
  read_manifest(abs);
  return ResultFiles(abs, identity_of(slurp(ResultFiles(abs, "").manifest_file())));
}

ResultFiles open_result_dir(const std::string& dir, const Manifest& manifest) {
  const Json want = manifest;
  ResultFiles files(fs::absolute(dir).lexically_normal().string(), "");
  // One writer: nothing is read or written in DIR before it is ours.
  files.lock_ = std::make_shared<const OutputLock>(OutputLock::directory(files.dir(), "the campaign directory"));
  std::error_code ec;
  if (fs::exists(files.manifest_file(), ec)) {
    check_same_campaign(files.dir(), want, parse_manifest(files.manifest_file()));
  } else {
    if (!fs::is_empty(files.dir(), ec)) {
      throw std::runtime_error(
          files.dir() + " is not empty and holds no campaign (no campaign.json; it holds " + some_entries(files.dir()) +
          "): a campaign directory is new, empty or the campaign's own; nothing in it was touched");
    }
    Manifest made = manifest;
    made.made = {{"unix_s", unix_time_s()}, {"host", host_name()}, {"pid", ::getpid()}};
    const Json m = made;
    fs::create_directories(files.runs_dir());
    write_file(files.manifest_file(), m.dump(2) + "\n");
    files.made_ = true;
  }
  files.identity_ = identity_of(slurp(files.manifest_file()));
  fs::create_directories(files.runs_dir());
  files.remove_partial();
  files.check_all();
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
      if (!pool.forget) results[i] = *kept;
    } else {
      todo.push_back(i);
    }
  }
  const std::size_t read = n - todo.size();
  PoolWork mapped;
  mapped.forget = pool.forget;
  mapped.work = [&](std::size_t k) { return pool.work(todo[k]); };
  mapped.died = [&](std::size_t k, const std::string& how) { return pool.died(todo[k], how); };
  if (pool.started) mapped.started = [&](std::size_t k) { pool.started(todo[k]); };
  mapped.finished = [&](std::size_t k, const std::string& result, std::size_t done) {
    if (files != nullptr && (!items.keep || items.keep(result))) files->write(items.keys[todo[k]], result);
    if (pool.finished) pool.finished(todo[k], result, read + done);
  };
  const std::vector<std::string> done = run_in_workers(todo.size(), jobs, mapped);
  if (!pool.forget) {
    for (std::size_t k = 0; k < todo.size(); ++k) results[todo[k]] = done[k];
  }
  return results;
}

}  // namespace nimble::campaign
