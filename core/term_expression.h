#pragma once
/// Generic terms: an expression of the states and inputs in a small grammar, the one
/// definition that a model file's `terms:` section (core/model.h), the plant's `plant.terms`
/// (plant/plant_model.h) and the identification (ident/identify.h) read. A term adds
/// coefficient * expression to one equation (docs/models.md, "Terms").
///
/// Grammar (whitespace is ignored):
///
///     expr    := product (('+' | '-') product)*
///     product := unary ('*' unary)*
///     unary   := '-' unary | power
///     power   := primary ('^' integer)?          integer in [0, 16]
///     primary := number | signal | '(' expr ')'
///              | ('abs' | 'sign' | 'pos' | 'neg') '(' expr ')'
///              | ('deadzone' | 'backlash' | 'lag' | 'sat' | 'ratelimit') '(' expr ',' number ')'
///
/// signal: a state or input by the name the model and the flight data use (p, v, phi, r, q,
/// u, w, theta, delta_f, delta_t, delta_d, delta_w; term_signal_names()). Operators:
///  - abs(x), sign(x) (-1, 0, 1), pos(x) = max(x, 0), neg(x) = min(x, 0);
///  - deadzone(x, w) = 0 for |x| <= w, x - w sign(x) beyond (w >= 0, the half-width);
///  - backlash(x, w): a play of half-width w: the output stays where it is until x is w away
///    from it, then follows at that distance (w >= 0; stateful, starts at x);
///  - lag(x, tau): first-order lag y' = (x - y) / tau, tau > 0 in s (stateful, starts at x);
///  - sat(x, s) = clamp(x, -s, s): an amplitude limit, s > 0 in x's unit;
///  - ratelimit(x, r): the output follows x as closely as a rate of at most r allows, r > 0 in
///    x's unit per second (stateful, starts at x). At each sample it is x clamped to
///    [y - r dt, y + r dt], y the output at the previous sample and dt the step since it: an
///    input slower than r passes unchanged at the same sample, a step is followed at r.
///
/// Evaluation: TermProgram binds an expression to an order of signals once; evaluate() then
/// reads the signals from an array, with no string work and no allocation. The stateful
/// operators keep their state in the program: evaluate() gives the value at the current
/// state, advance(dt) moves the state over dt with the inputs of the last evaluate() held
/// (a backlash and a rate limit keep the output of the last evaluate(); a rate limit's next
/// output may move from it by r dt).

#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

namespace nimble {

/// An expression that does not parse: the position (0-based character offset) and the problem.
class TermParseError : public std::invalid_argument {
 public:
  TermParseError(std::string text, std::size_t position, std::string problem);
  std::size_t position() const { return position_; }
  const std::string& problem() const { return problem_; }

 private:
  std::size_t position_;
  std::string problem_;
};

/// Signals a term may read: the states and inputs of every model structure.
const std::vector<std::string>& term_signal_names();

/// A parsed expression (immutable; copies share the tree).
class TermExpression {
 public:
  struct Node;

  /// @throws TermParseError naming the position, what was expected and what was found.
  static TermExpression parse(const std::string& text);

  /// Text that parses to the same expression (minimal parentheses, numbers round-trip exact).
  std::string to_string() const;
  /// Signals it reads, sorted, each once.
  std::vector<std::string> signals() const;
  /// Has a stateful operator (backlash, lag, ratelimit).
  bool stateful() const;
  /// Same tree (operators, signals, numbers bit for bit).
  bool same_as(const TermExpression& other) const;

  const Node& root() const { return *root_; }

 private:
  std::shared_ptr<const Node> root_;
};

/// An expression bound to an order of signals, ready to evaluate fast.
class TermProgram {
 public:
  TermProgram() = default;
  /// @throws std::invalid_argument naming a signal of `expression` that `signal_order` lacks.
  TermProgram(const TermExpression& expression, const std::vector<std::string>& signal_order);

  /// Value at `signals` (indexed as signal_order) and the current state. A stateful operator
  /// that has not yet seen an input starts at it. No allocation.
  double evaluate(const double* signals);
  /// Moves the state over `dt_s` with the inputs of the last evaluate() held (exact for a lag);
  /// a backlash and a rate limit commit the output of the last evaluate().
  void advance(double dt_s);
  /// Forgets the state: the next evaluate() starts every stateful operator at its input.
  void reset();

 private:
  enum class Op {
    kConst,
    kSignal,
    kAdd,
    kSub,
    kMul,
    kNeg,
    kPow,
    kAbs,
    kSign,
    kPos,
    kNeg0,
    kDeadzone,
    kSat,
    kBacklash,
    kLag,
    kRateLimit
  };
  struct Instr {
    Op op;
    double value = 0.0;  ///< constant, width, limit, time constant or rate
    int index = 0;       ///< signal slot, power, or state slot
  };
  void emit(const TermExpression::Node& node, const std::vector<std::string>& order, int depth);

  std::vector<Instr> code_;
  std::vector<double> stack_;
  std::vector<double> state_;    ///< per stateful operator
  std::vector<double> pending_;  ///< backlash, ratelimit: output of the last evaluate; lag: its input
  std::vector<char> started_;
  double dt_s_ = 0.0;  ///< the last advance()'s step: a rate limit's output moves by r dt_s_ at most
  int max_depth_ = 0;
};

/// Values of `expression` along a record: `columns[i]` holds signal `names[i]` at every sample,
/// sample k is evaluated at the state reached after k steps of dt_s (a stateful operator starts
/// at the first sample's input). @throws std::invalid_argument if a signal is missing or the
/// columns differ in length.
std::vector<double> evaluate_along(const TermExpression& expression, const std::vector<std::string>& names,
                                   const std::vector<const std::vector<double>*>& columns, double dt_s);

}  // namespace nimble
