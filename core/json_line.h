#pragma once
/// How the rig writes a JSON document (every report's `--json`): on one line, keys in the order
/// they were put, numbers as the shortest text that reads back to the same double, a non-finite
/// number as null, bytes that are not UTF-8 replaced by U+FFFD instead of failing. Debian's
/// nlohmann-json3-dev (header-only).

#include <complex>
#include <string>

#include <nlohmann/json.hpp>

namespace nimble {

/// A document whose keys keep the order they were put in.
using OrderedJson = nlohmann::ordered_json;

/// `j` as the rig writes it.
inline std::string json_line(const OrderedJson& j) {
  return j.dump(-1, ' ', false, OrderedJson::error_handler_t::replace);
}

/// JSON string literal of `s`, with quotes and escapes.
inline std::string json_quote(const std::string& s) { return json_line(OrderedJson(s)); }

/// A complex number as the rig writes it: [re, im].
inline OrderedJson complex_json(const std::complex<double>& z) { return OrderedJson::array({z.real(), z.imag()}); }

}  // namespace nimble
