#include "core/config.h"

#include <cctype>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/yaml_input.h"

namespace nimble {
namespace {

std::string format_error(const std::string& file, const std::string& key, const std::string& value,
                         const std::string& problem, int line) {
  std::ostringstream out;
  out << file;
  if (line > 0) out << ":" << line;
  out << ": ";
  if (!key.empty()) out << "key '" << key << "': ";
  if (!value.empty()) out << "value '" << value << "': ";
  out << problem;
  return out.str();
}

int line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? -1 : mark.line + 1;
}

std::string format_number(double x) {
  std::ostringstream out;
  out << x;
  return out.str();
}

}  // namespace

ConfigError::ConfigError(std::string file, std::string key, std::string value, std::string problem, int line)
    : std::runtime_error(format_error(file, key, value, problem, line)),
      file_(std::move(file)),
      key_(std::move(key)),
      value_(std::move(value)),
      problem_(std::move(problem)),
      line_(line) {}

std::string general_text(double x) { return fmt("%g", x); }

std::string fmt(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string shortest_text(double x) {
  char text[40];
  for (int digits = 15; digits <= 17; ++digits) {
    std::snprintf(text, sizeof text, "%.*g", digits, x);
    if (std::strtod(text, nullptr) == x) break;
  }
  return text;
}

bool Range::contains(double x) const {
  const bool above = lo_open ? x > lo : x >= lo;
  const bool below = hi_open ? x < hi : x <= hi;
  return above && below;
}

std::string Range::describe() const {
  const bool has_lo = std::isfinite(lo);
  const bool has_hi = std::isfinite(hi);
  if (has_lo && has_hi) {
    return std::string("in ") + (lo_open ? "(" : "[") + format_number(lo) + ", " + format_number(hi) +
           (hi_open ? ")" : "]");
  }
  if (has_lo) return (lo_open ? "> " : ">= ") + format_number(lo);
  if (has_hi) return (hi_open ? "< " : "<= ") + format_number(hi);
  return "finite";
}

std::string yaml_text(const YAML::Node& node) {
  if (!node.IsDefined() || node.IsNull()) return "";
  if (node.IsScalar()) return node.Scalar();
  YAML::Emitter emitter;
  emitter << YAML::Flow << node;
  std::string text = emitter.c_str();
  if (text.size() > 60) text = text.substr(0, 57) + "...";
  return text;
}

ConfigMap::ConfigMap(YAML::Node node, std::string file, std::string path)
    : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {
  if (!node_.IsMap()) {
    throw ConfigError(
        file_, path_, yaml_text(node_),
        path_.empty() ? "the file must hold a YAML mapping (key: value pairs)" : "must be a mapping (key: value pairs)",
        line_of(node_));
  }
}

namespace {

void check_unique_keys_at(const YAML::Node& node, const std::string& file, const std::string& path) {
  if (node.IsMap()) {
    std::map<std::string, int> seen;  // key -> line
    for (auto it = node.begin(); it != node.end(); ++it) {
      if (!it->first.IsScalar()) {
        // Every reader takes keys as names (ConfigMap, scenario merging): `[a, b]: 1` or
        // `? {a: 1}` would end it with yaml-cpp's conversion error instead of this one.
        throw ConfigError(file, path, "", "a key must be a plain name, not a list, mapping or null",
                          it->first.Mark().line + 1);
      }
      const std::string key = it->first.Scalar();
      const std::string key_path = path.empty() ? key : path + "." + key;
      const int line = it->first.Mark().line + 1;
      const auto [where, fresh] = seen.emplace(key, line);
      if (!fresh) {
        throw ConfigError(file, key_path, "",
                          "key given twice (lines " + std::to_string(where->second) + " and " + std::to_string(line) +
                              "); give it once",
                          line);
      }
      check_unique_keys_at(it->second, file, key_path);
    }
  } else if (node.IsSequence()) {
    std::size_t i = 0;
    for (auto it = node.begin(); it != node.end(); ++it, ++i) {
      check_unique_keys_at(*it, file, path + "[" + std::to_string(i) + "]");
    }
  }
}

}  // namespace

void check_unique_keys(const YAML::Node& root, const std::string& file) { check_unique_keys_at(root, file, ""); }

ConfigMap ConfigMap::load_file(const std::string& file) {
  const YAML::Node root = load_yaml_file(file);
  check_unique_keys(root, file);
  return ConfigMap(root, file, "");
}

ConfigMap ConfigMap::load_string(const std::string& text, const std::string& origin) {
  const YAML::Node root = load_yaml_text(text, origin);
  check_unique_keys(root, origin);
  return ConfigMap(root, origin, "");
}

bool ConfigMap::has(const std::string& key) const { return static_cast<bool>(node_[key]); }

std::string ConfigMap::key_path(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }

std::string ConfigMap::directory() const { return std::filesystem::path(file_).parent_path().string(); }

void ConfigMap::fail(const std::string& key, const std::string& problem) const {
  const YAML::Node node = node_[key];
  throw ConfigError(file_, key_path(key), node ? yaml_text(node) : "", problem, node ? line_of(node) : line_of(node_));
}

YAML::Node ConfigMap::require(const std::string& key) {
  used_.insert(key);
  YAML::Node node = node_[key];
  if (!node) {
    throw ConfigError(file_, key_path(key), "", "missing required key", line_of(node_));
  }
  return node;
}

double ConfigMap::parse_double(const std::string& key, const YAML::Node& node) const {
  if (!node.IsScalar()) fail(key, "must be a number");
  const std::string& text = node.Scalar();
  // Parse the whole scalar ourselves: yaml-cpp accepts ".nan"/".inf", and a
  // unit written after the number ("29.5 g") must not be silently dropped.
  std::string lower;
  for (const char c : text) lower += static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  if (lower.find("nan") != std::string::npos || lower.find("inf") != std::string::npos) {
    fail(key, "must be a finite number");
  }
  std::size_t consumed = 0;
  double value = 0.0;
  try {
    value = std::stod(text, &consumed);
  } catch (const std::exception&) {
    fail(key, "must be a number");
  }
  while (consumed < text.size() && std::isspace(static_cast<unsigned char>(text[consumed]))) {
    ++consumed;
  }
  if (consumed != text.size()) fail(key, "must be a number (no units or text after it)");
  if (!std::isfinite(value)) fail(key, "must be a finite number");
  return value;
}

double ConfigMap::get_double(const std::string& key, const Range& range) {
  const double value = parse_double(key, require(key));
  if (!range.contains(value)) fail(key, "must be " + range.describe());
  return value;
}

double ConfigMap::get_double_or(const std::string& key, double fallback, const Range& range) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return get_double(key, range);
}

long long ConfigMap::get_int(const std::string& key, const Range& range) {
  const double value = parse_double(key, require(key));
  if (value != std::floor(value) || std::fabs(value) > 9.0e15) {
    fail(key, "must be a whole number");
  }
  if (!range.contains(value)) fail(key, "must be " + range.describe());
  return static_cast<long long>(value);
}

std::string ConfigMap::get_string(const std::string& key) {
  const YAML::Node node = require(key);
  if (!node.IsScalar() || node.Scalar().empty()) fail(key, "must be a non-empty string");
  return node.Scalar();
}

std::string ConfigMap::get_string_or(const std::string& key, const std::string& fallback) {
  if (!has(key)) {
    used_.insert(key);
    return fallback;
  }
  return get_string(key);
}

std::string ConfigMap::get_enum(const std::string& key, const std::vector<std::string>& allowed) {
  const std::string value = get_string(key);
  for (const auto& option : allowed) {
    if (value == option) return value;
  }
  std::string list;
  for (const auto& option : allowed) list += (list.empty() ? "" : ", ") + option;
  fail(key, "must be one of: " + list);
}

bool ConfigMap::get_bool(const std::string& key) {
  const YAML::Node node = require(key);
  if (node.IsScalar()) {
    const std::string& text = node.Scalar();
    if (text == "true") return true;
    if (text == "false") return false;
  }
  fail(key, "must be true or false");
}

std::vector<std::string> ConfigMap::get_string_list(const std::string& key) {
  const YAML::Node node = require(key);
  if (!node.IsSequence()) fail(key, "must be a list of strings");
  std::vector<std::string> out;
  for (const auto& item : node) {
    if (!item.IsScalar() || item.Scalar().empty()) fail(key, "must be a list of non-empty strings");
    out.push_back(item.Scalar());
  }
  return out;
}

ConfigMap ConfigMap::get_map(const std::string& key) { return ConfigMap(require(key), file_, key_path(key)); }

YAML::Node ConfigMap::get_node(const std::string& key) { return require(key); }

std::vector<std::string> ConfigMap::keys() const {
  std::vector<std::string> out;
  for (const auto& item : node_) out.push_back(item.first.as<std::string>());
  return out;
}

void ConfigMap::finish() const {
  std::vector<std::string> known(used_.begin(), used_.end());
  for (const auto& item : node_) {
    const std::string key = item.first.as<std::string>();
    if (used_.count(key) == 0) {
      std::string list;
      for (const auto& k : known) list += (list.empty() ? "" : ", ") + k;
      throw ConfigError(file_, key_path(key), yaml_text(item.second), "unknown key (known keys here: " + list + ")",
                        line_of(item.first));
    }
  }
}

}  // namespace nimble
