#pragma once
/// Strict YAML configuration reading.
///
/// Every configuration file of the rig is read through ConfigMap, which
///  - names the file, the full key path, the offending value and (where known)
///    the line in every error;
///  - treats a missing required key, an unknown key, a non-numeric or
///    non-finite number and an out-of-range value as errors (no silent default);
///  - lets a loader state defaults explicitly (`get_double_or`).
/// Errors are thrown as ConfigError at load time; nothing here is meant to run
/// inside a control loop.

#include <limits>
#include <optional>
#include <set>
#include <stdexcept>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace nimble {

/// A configuration error: which file, which key, which value, and what is wrong.
class ConfigError : public std::runtime_error {
 public:
  ConfigError(std::string file, std::string key, std::string value, std::string problem, int line = -1);

  const std::string& file() const { return file_; }
  /// Dotted key path, e.g. "inertia_kgm2.Ixx"; empty for file-level errors.
  const std::string& key() const { return key_; }
  /// The offending value as written in the file; empty when the key is missing.
  const std::string& value() const { return value_; }
  const std::string& problem() const { return problem_; }
  /// 1-based line in the file, or -1 when unknown.
  int line() const { return line_; }

 private:
  std::string file_, key_, value_, problem_;
  int line_;
};

/// Refuses a YAML mapping (anywhere in `root`) that gives one key twice: yaml-cpp keeps both and
/// answers with one of them, so that a value written later in the file could silently lose.
/// Refuses as well a key that is not a plain name (a list, a mapping or null).
/// @throws ConfigError naming `file`, the key path and both lines (or the key's line).
void check_unique_keys(const YAML::Node& root, const std::string& file);

/// Closed or open interval used to validate numeric config values.
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;

  static Range any() { return {}; }
  /// (0, +inf)
  static Range positive() { return {0.0, std::numeric_limits<double>::infinity(), true, false}; }
  /// [0, +inf)
  static Range non_negative() { return {0.0, std::numeric_limits<double>::infinity(), false, false}; }
  /// [lo, hi]
  static Range closed(double lo, double hi) { return {lo, hi, false, false}; }

  bool contains(double x) const;
  /// Human-readable form, e.g. "> 0" or "in [0, 1]".
  std::string describe() const;
};

/// The shortest text that reads back as `x` (15 to 17 significant digits): a number written into
/// an override or a file, read back to the same double.
std::string shortest_text(double x);

/// `x` as printf's %g writes it (six significant digits): numbers in messages.
std::string general_text(double x);

/// `x` formatted with the printf `format` (one double conversion; at most 63 characters):
/// numbers in reports and plots.
std::string fmt(const char* format, double x);

/// One YAML mapping of a config file, with strict key accounting.
///
/// Each accessor marks its key as used; `finish()` then reports any key that
/// no accessor asked for, so a misspelt key is an error instead of being ignored.
class ConfigMap {
 public:
  /// Wraps `node` (must be a mapping) found at `path` inside `file`.
  /// @throws ConfigError if `node` is not a mapping.
  ConfigMap(YAML::Node node, std::string file, std::string path);

  /// Parses `file` (read within its bounds: core/yaml_input.h) and returns its root mapping.
  /// @throws ConfigError if the file cannot be read, is no regular file, is above the bound of a
  ///         configuration file, is not valid YAML, expands its aliases past the bounds or its root
  ///         is not a mapping.
  static ConfigMap load_file(const std::string& file);

  /// Parses YAML text (for tests and inline overrides); `origin` names it in errors.
  static ConfigMap load_string(const std::string& text, const std::string& origin);

  bool has(const std::string& key) const;

  /// Required finite number within `range`.
  double get_double(const std::string& key, const Range& range = Range::any());
  /// Optional finite number within `range`; `fallback` when the key is absent.
  double get_double_or(const std::string& key, double fallback, const Range& range = Range::any());
  /// Required integer within `range`.
  long long get_int(const std::string& key, const Range& range = Range::any());
  /// Required non-empty string.
  std::string get_string(const std::string& key);
  /// Optional string; `fallback` when absent.
  std::string get_string_or(const std::string& key, const std::string& fallback);
  /// Required string that must be one of `allowed`.
  std::string get_enum(const std::string& key, const std::vector<std::string>& allowed);
  /// Required boolean (true/false).
  bool get_bool(const std::string& key);
  /// Required sequence of strings.
  std::vector<std::string> get_string_list(const std::string& key);
  /// Required nested mapping.
  ConfigMap get_map(const std::string& key);
  /// Required raw node (for structures the caller validates itself).
  YAML::Node get_node(const std::string& key);

  /// Every key of this mapping, in file order.
  std::vector<std::string> keys() const;

  /// @throws ConfigError naming the first key that no accessor used.
  void finish() const;

  /// Throws a ConfigError for `key` of this map with its value as written.
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;

  /// Dotted path of `key` inside the file.
  std::string key_path(const std::string& key) const;
  const std::string& file() const { return file_; }
  /// Directory of the file, to resolve relative paths it contains.
  std::string directory() const;

 private:
  YAML::Node require(const std::string& key);
  double parse_double(const std::string& key, const YAML::Node& node) const;

  YAML::Node node_;
  std::string file_;
  std::string path_;
  std::set<std::string> used_;
};

/// Text of a scalar node as written (or a short form of a non-scalar node).
std::string yaml_text(const YAML::Node& node);

}  // namespace nimble
