#pragma once
/// The `terms:` section of a model file and the `terms` list of the plant section: generic
/// terms in the grammar of core/term_expression.h, each adding coefficient * expression to one
/// equation, read and validated in one place (docs/models.md, "Terms").

#include <string>
#include <vector>

#include "core/config.h"
#include "core/term_expression.h"

namespace nimble {

/// One generic term: `coefficient * expression` added to `equation`'s force or moment, in the
/// units of that equation's derivatives (L, M, N: N m; X, Y, Z: N), so the coefficient is in
/// N m (or N) per unit of the expression (e.g. N m s^3/rad^3 for L with p^3).
struct Term {
  std::string equation;  ///< "L", "Y", "N", "X", "Z" or "M"
  TermExpression expression;
  double coefficient = 0.0;
  std::string where;  ///< "file:line" it was read from (messages)
};

/// Reads the list `key` of `parent`: each entry a mapping {equation, expression, coefficient}.
/// @throws ConfigError naming the file, line and key of an entry that is not a mapping, has an
///         unknown or missing key, an equation outside `equations`, an expression that does not
///         parse (with the position) or reads a signal outside `signals`, or a coefficient that
///         is not a finite number.
std::vector<Term> terms_from_config(ConfigMap& parent, const std::string& key,
                                    const std::vector<std::string>& equations, const std::vector<std::string>& signals);

/// Name of a term's coefficient in an identification's parameter list: "<equation>:<expression>",
/// e.g. "L:p^3".
std::string term_parameter_name(const Term& term);

}  // namespace nimble
