#include "effects/effect.h"

#include <cctype>
#include <cstdio>

namespace nimble::effects {
namespace {

/// `x` as the grammar reads it back exactly, in parentheses if negative.
std::string exact_number(double x) {
  char buf[40];
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return x < 0.0 ? std::string("(") + buf + ")" : std::string(buf);
}

bool word_char(char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; }

}  // namespace

std::string EffectDefinition::scan_parameter() const {
  switch (scan) {
    case Scan::kDelay: return "delay_s";
    case Scan::kChangeTime: return "t_change_s";
    case Scan::kFrequency: return "flapping_hz";
    case Scan::kFormParameter:
    case Scan::kNone: break;
  }
  return "";
}

std::string column_term(const EffectColumn& c, double u0_mps, double w0_mps) {
  std::string out;
  const std::string& t = c.term;
  for (std::size_t i = 0; i < t.size();) {
    std::size_t j = i;
    while (j < t.size() && word_char(t[j])) ++j;
    if (j == i) {
      out += t[i++];
      continue;
    }
    const std::string word = t.substr(i, j - i);
    out += word == "u0" ? exact_number(u0_mps) : word == "w0" ? exact_number(w0_mps) : word;
    i = j;
  }
  return out;
}

}  // namespace nimble::effects
