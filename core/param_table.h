#pragma once
/// Parameter tables: each configuration parameter's key, range, unit and meaning declared once,
/// next to its struct, and used by
///  - the loader (read_params: a ConfigMap key within its range, or the struct's default),
///  - validation of a struct built in code (check_params: the same ranges),
///  - the documentation (params_markdown: key, default, range, unit, meaning; `rig params`).
/// The default is the struct's own initialiser, so it too is written once.
///
/// A parameter is a double, an integer, a boolean or a 3-vector (written as a mapping of its
/// axis names, x y z unless the parameter names others, each component within the range). A key
/// "group.name" lives in the section's sub-mapping `group`: the loader reads a group with
/// read_params(sub_map, table, config, "group").

#include <cmath>
#include <cstdint>
#include <optional>
#include <sstream>
#include <stdexcept>
#include <string>
#include <type_traits>
#include <variant>
#include <vector>

#include <Eigen/Core>

#include "core/config.h"
#include "core/config_fields.h"

namespace nimble {

template <typename Config>
struct Param {
  using Member =
      std::variant<double Config::*, Eigen::Vector3d Config::*, bool Config::*, int Config::*, std::int64_t Config::*>;
  std::string key;
  Member member;
  Range range;                ///< of the value (of each component of a vector); unused for booleans
  std::string unit;           ///< e.g. "rad/s", "-" for none
  std::string meaning;        ///< one line, with its source where it has one
  AxisNames axes = kXyzAxes;  ///< a vector's component keys
};

template <typename Config>
using ParamTable = std::vector<Param<Config>>;

namespace param_detail {

inline std::string number(double x) {
  std::ostringstream s;
  s.precision(10);
  s << x;
  return s.str();
}

}  // namespace param_detail

namespace param_detail {

/// The key of `p` within `group` ("" for the section itself), or "" if it is not in the group.
inline std::string key_in_group(const std::string& key, const std::string& group) {
  if (group.empty()) return key.find('.') == std::string::npos ? key : "";
  if (key.size() <= group.size() + 1 || key.compare(0, group.size(), group) != 0 || key[group.size()] != '.') return "";
  const std::string rest = key.substr(group.size() + 1);
  return rest.find('.') == std::string::npos ? rest : "";
}

}  // namespace param_detail

/// Reads every parameter of `table` in `group` ("": the keys without a dot) that `map` has into
/// `config`, each within its range; an absent key leaves the struct's default. Does not call
/// map.finish(): the caller may read more.
/// @throws ConfigError naming the file, key and value.
template <typename Config>
void read_params(ConfigMap& map, const ParamTable<Config>& table, Config& config, const std::string& group = "") {
  for (const Param<Config>& p : table) {
    const std::string key = param_detail::key_in_group(p.key, group);
    if (key.empty()) continue;
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(config.*member)>;
          T& field = config.*member;
          if constexpr (std::is_same_v<T, double>) {
            field = map.get_double_or(key, field, p.range);
          } else if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
            field = get_vec3_or(map, key, field, p.range, p.axes);
          } else if constexpr (std::is_same_v<T, bool>) {
            field = get_bool_or(map, key, field);
          } else {
            field = static_cast<T>(get_int_or(map, key, static_cast<long long>(field), p.range));
          }
        },
        p.member);
  }
}

/// A parameter outside its range: its key (a vector's component as key[i]), value and range.
struct ParamViolation {
  std::string key;
  std::string value;
  std::string allowed;  ///< e.g. "> 0", "in [0, 1]"
};

/// The first parameter of `config` outside its range (or not finite), if any.
template <typename Config>
std::optional<ParamViolation> first_violation(const ParamTable<Config>& table, const Config& config) {
  using param_detail::number;
  std::optional<ParamViolation> found;
  for (const Param<Config>& p : table) {
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(config.*member)>;
          const T& field = config.*member;
          if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
            for (int i = 0; i < 3 && !found; ++i) {
              if (!std::isfinite(field[i]) || !p.range.contains(field[i])) {
                // Index notation: the struct's component, as code built it.
                found = ParamViolation{p.key + "[" + std::to_string(i) + "]", number(field[i]), p.range.describe()};
              }
            }
          } else if constexpr (!std::is_same_v<T, bool>) {
            const double x = static_cast<double>(field);
            if (!std::isfinite(x) || !p.range.contains(x)) found = ParamViolation{p.key, number(x), p.range.describe()};
          }
        },
        p.member);
    if (found) break;
  }
  return found;
}

/// Checks every parameter of `config` against its range (and for finiteness).
/// @throws std::invalid_argument "key = value: must be <range>".
template <typename Config>
void check_params(const ParamTable<Config>& table, const Config& config) {
  if (const auto v = first_violation(table, config)) {
    throw std::invalid_argument(v->key + " = " + v->value + ": must be " + v->allowed);
  }
}

/// The header of a parameter table in Markdown (params_markdown()).
inline constexpr const char* kParamsMarkdownHeader =
    "| key | default | allowed | unit | meaning |\n|---|---|---|---|---|\n";

/// The rows of the table in Markdown, one per parameter (key after `prefix`, default from
/// `defaults`, allowed range, unit, meaning), without the header: tables of one section join up.
template <typename Config>
std::string params_markdown_rows(const ParamTable<Config>& table, const Config& defaults,
                                 const std::string& prefix = "") {
  using param_detail::number;
  std::ostringstream out;
  for (const Param<Config>& p : table) {
    std::string value;
    bool is_bool = false;
    std::visit(
        [&](auto member) {
          using T = std::decay_t<decltype(defaults.*member)>;
          const T& field = defaults.*member;
          if constexpr (std::is_same_v<T, Eigen::Vector3d>) {
            value = std::string("{") + p.axes[0] + ": " + number(field[0]) + ", " + p.axes[1] + ": " +
                    number(field[1]) + ", " + p.axes[2] + ": " + number(field[2]) + "}";
          } else if constexpr (std::is_same_v<T, bool>) {
            value = field ? "true" : "false";
            is_bool = true;
          } else {
            value = number(static_cast<double>(field));
          }
        },
        p.member);
    std::string meaning;  // a '|' would end the cell
    for (const char c : p.meaning) meaning += c == '|' ? std::string("\\|") : std::string(1, c);
    out << "| `" << prefix << p.key << "` | " << value << " | " << (is_bool ? "true, false" : p.range.describe())
        << " | " << p.unit << " | " << meaning << " |\n";
  }
  return out.str();
}

/// The table as Markdown: the header and the rows of params_markdown_rows().
template <typename Config>
std::string params_markdown(const ParamTable<Config>& table, const Config& defaults, const std::string& prefix = "") {
  return kParamsMarkdownHeader + params_markdown_rows(table, defaults, prefix);
}

}  // namespace nimble
