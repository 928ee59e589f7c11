#pragma once
/// One effect of a derivative model's `effects:` section (written by `rig discrepancy
/// --model-out`, core/model.h) as the plant reads it: its parameters by name, with the checks
/// every effect's from-model mapping uses and errors that name the model, the effect and the
/// parameter. The ranges are those of the plant effect's parameter table, so that a value the
/// plant file may not hold cannot come in through a model either.

#include <functional>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/param_table.h"

namespace nimble::effects {

/// Bounds of the derivatives a model's effects: section may set (wide sanity bounds: |L| terms
/// up to 0.1 N m per unit, |Y| terms up to 1 N per unit).
inline const Range kRollDerivativeRange = Range::closed(-0.1, 0.1);
inline const Range kSideDerivativeRange = Range::closed(-1.0, 1.0);

struct ModelSection {
  const DerivativeModel& model;
  const std::string& effect;
  const std::map<std::string, double>& params;

  /// "plant: model 'NAME' (FILE), effects.EFFECT".
  std::string where() const;
  [[noreturn]] void fail(const std::string& problem) const;
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;

  /// Refuses a parameter `known` does not accept (naming `expected`), and non-finite values.
  void check_keys(const std::function<bool(const std::string&)>& known, const std::string& expected) const;
  /// Refuses a parameter not in `names`, and non-finite values.
  void check_keys(const std::vector<std::string>& names) const;

  /// The value of `key`, 0 if the section does not carry it; refused outside `range`.
  double or_zero(const std::string& key, const Range& range) const;
  /// The value of `key`, which the section must carry; refused outside `range`.
  double required(const std::string& key, const Range& range) const;
  /// Refuses `value` of `key` outside `range`.
  void in_range(const std::string& key, double value, const Range& range) const;
  /// Sets derivative `key` of `derivatives` from the section (one the section does not carry
  /// is left as the model has it). Refuses one the model also carries among its derivatives:
  /// the two would be two values of one term.
  void set_derivative(const std::string& key, std::map<std::string, double>& derivatives, const Range& range) const;
};

/// The range of `key` in `table`. @throws std::logic_error if the table has no such key.
template <typename Config>
const Range& range_of(const ParamTable<Config>& table, const std::string& key) {
  for (const auto& p : table) {
    if (p.key == key) return p.range;
  }
  throw std::logic_error("no parameter " + key + " in the table");
}

}  // namespace nimble::effects
