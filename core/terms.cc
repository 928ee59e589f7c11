#include "core/terms.h"

#include <algorithm>

namespace nimble {

namespace {
std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ", ") + s;
  return out;
}
}  // namespace

std::vector<Term> terms_from_config(ConfigMap& parent, const std::string& key,
                                    const std::vector<std::string>& equations,
                                    const std::vector<std::string>& signals) {
  std::vector<Term> out;
  const YAML::Node list = parent.get_node(key);
  if (!list.IsSequence()) parent.fail(key, "must be a list of terms, each {equation, expression, coefficient}");
  for (std::size_t i = 0; i < list.size(); ++i) {
    const std::string path = parent.key_path(key) + "[" + std::to_string(i) + "]";
    ConfigMap entry(list[i], parent.file(), path);
    Term t;
    t.equation = entry.get_enum("equation", equations);
    const std::string text = entry.get_string("expression");
    try {
      t.expression = TermExpression::parse(text);
    } catch (const TermParseError& e) {
      entry.fail("expression", "does not parse: at position " + std::to_string(e.position() + 1) + ": " + e.problem());
    }
    for (const auto& s : t.expression.signals()) {
      if (std::find(signals.begin(), signals.end(), s) == signals.end()) {
        entry.fail("expression", "reads an unknown signal '" + s + "' (known: " + join(signals) + ")");
      }
    }
    t.coefficient = entry.get_double("coefficient");
    const int line = list[i].Mark().is_null() ? -1 : list[i].Mark().line + 1;
    t.where = parent.file() + (line > 0 ? ":" + std::to_string(line) : "");
    entry.finish();
    out.push_back(std::move(t));
  }
  return out;
}

std::string term_parameter_name(const Term& term) { return term.equation + ":" + term.expression.to_string(); }

}  // namespace nimble
