#include "core/term_expression.h"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <set>

namespace nimble {

struct TermExpression::Node {
  enum class Kind { kNumber, kSignal, kAdd, kSub, kMul, kNeg, kPow, kCall };
  Kind kind = Kind::kNumber;
  double number = 0.0;  ///< kNumber; the parameter of a two-argument call
  std::string name;     ///< kSignal; function name of kCall
  int power = 0;        ///< kPow
  std::vector<std::shared_ptr<const Node>> children;
};

namespace {

using Node = TermExpression::Node;
using NodePtr = std::shared_ptr<const Node>;

const std::vector<std::string>& one_argument_functions() {
  static const std::vector<std::string> names{"abs", "sign", "pos", "neg"};
  return names;
}
const std::vector<std::string>& two_argument_functions() {
  static const std::vector<std::string> names{"deadzone", "backlash", "lag", "sat", "ratelimit"};
  return names;
}

/// The number argument of a two-argument function: its letter, what it is, and, where it must
/// be positive, the problem a non-positive one is refused with.
struct Parameter {
  const char* letter;
  const char* meaning;
  const char* positive;  ///< nullptr: any number >= 0 (the grammar's numbers have no sign)
};
Parameter parameter_of(const std::string& function) {
  if (function == "lag") return {"tau", "the time constant tau [s]", "a time constant tau > 0 s"};
  if (function == "sat") return {"s", "the limit s", "a limit s > 0"};
  if (function == "ratelimit") return {"r", "the rate r [per s]", "a rate r > 0 per second"};
  return {"w", "the width w", nullptr};
}
bool contains(const std::vector<std::string>& v, const std::string& s) {
  return std::find(v.begin(), v.end(), s) != v.end();
}

/// The shortest text that reads back as x, fixed or scientific, whichever is shorter (900, not
/// 9e+02; 1e-05, not 0.00001).
std::string format_number(double x) {
  char buf[40];
  const auto end = std::to_chars(buf, buf + sizeof buf, x).ptr;
  return std::string(buf, end);
}

class Parser {
 public:
  explicit Parser(const std::string& text) : text_(text) {}

  NodePtr parse() {
    NodePtr e = expr();
    skip_space();
    if (pos_ < text_.size()) fail("expected an operator (+, -, *, ^) or the end of the expression");
    return e;
  }

 private:
  [[noreturn]] void fail(const std::string& expected) const {
    throw TermParseError(text_, pos_, expected + ", found " + found());
  }
  std::string found() const {
    if (pos_ >= text_.size()) return "the end";
    std::size_t end = pos_ + 1;
    const bool negative_number = text_[pos_] == '-' && end < text_.size() &&
                                 (std::isdigit(static_cast<unsigned char>(text_[end])) || text_[end] == '.');
    if (negative_number || std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_' ||
        text_[pos_] == '.') {
      while (end < text_.size() &&
             (std::isalnum(static_cast<unsigned char>(text_[end])) || text_[end] == '_' || text_[end] == '.'))
        ++end;
    }
    return "'" + text_.substr(pos_, end - pos_) + "'";
  }
  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
  }
  bool accept(char c) {
    skip_space();
    if (pos_ < text_.size() && text_[pos_] == c) {
      ++pos_;
      return true;
    }
    return false;
  }
  void expect(char c, const std::string& what) {
    if (!accept(c)) fail("expected " + what);
  }
  static NodePtr make(Node::Kind kind, std::vector<NodePtr> children) {
    auto n = std::make_shared<Node>();
    n->kind = kind;
    n->children = std::move(children);
    return n;
  }

  NodePtr expr() {
    NodePtr left = product();
    for (;;) {
      if (accept('+'))
        left = make(Node::Kind::kAdd, {left, product()});
      else if (accept('-'))
        left = make(Node::Kind::kSub, {left, product()});
      else
        return left;
    }
  }
  NodePtr product() {
    NodePtr left = unary();
    while (accept('*')) left = make(Node::Kind::kMul, {left, unary()});
    return left;
  }
  NodePtr unary() {
    if (accept('-')) return make(Node::Kind::kNeg, {unary()});
    return power();
  }
  NodePtr power() {
    NodePtr base = primary();
    if (!accept('^')) return base;
    skip_space();
    std::size_t start = pos_;
    while (pos_ < text_.size() && std::isdigit(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    if (start == pos_) fail("expected an integer power in [0, 16] after '^'");
    int value = 17;
    std::from_chars(text_.data() + start, text_.data() + pos_, value);
    if (value > 16 || pos_ - start > 2) {
      pos_ = start;
      fail("expected an integer power in [0, 16]");
    }
    if (pos_ < text_.size() && (text_[pos_] == '.' || text_[pos_] == 'e' || text_[pos_] == 'E')) {
      pos_ = start;
      fail("expected an integer power in [0, 16]");
    }
    auto n = std::make_shared<Node>();
    n->kind = Node::Kind::kPow;
    n->power = value;
    n->children = {base};
    return n;
  }
  double number(const std::string& what) {
    skip_space();
    std::size_t start = pos_;
    double value = 0.0;
    if (pos_ < text_.size() && (std::isdigit(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '.')) {
      auto [ptr, ec] = std::from_chars(text_.data() + pos_, text_.data() + text_.size(), value);
      if (ec == std::errc() && std::isfinite(value)) {
        pos_ = static_cast<std::size_t>(ptr - text_.data());
        if (pos_ < text_.size() && (std::isalpha(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_')) {
          fail("expected an operator after the number " + text_.substr(start, pos_ - start));
        }
        return value;
      }
    }
    fail("expected " + what);
  }
  NodePtr primary() {
    skip_space();
    if (pos_ >= text_.size()) fail("expected a number, a signal, a function or '('");
    char c = text_[pos_];
    if (c == '(') {
      ++pos_;
      NodePtr e = expr();
      expect(')', "')'");
      return e;
    }
    if (std::isdigit(static_cast<unsigned char>(c)) || c == '.') {
      auto n = std::make_shared<Node>();
      n->kind = Node::Kind::kNumber;
      n->number = number("a number");
      return n;
    }
    if (std::isalpha(static_cast<unsigned char>(c)) || c == '_') {
      std::size_t start = pos_;
      while (pos_ < text_.size() && (std::isalnum(static_cast<unsigned char>(text_[pos_])) || text_[pos_] == '_'))
        ++pos_;
      std::string name = text_.substr(start, pos_ - start);
      bool one = contains(one_argument_functions(), name);
      bool two = contains(two_argument_functions(), name);
      if (!one && !two) {
        auto n = std::make_shared<Node>();
        n->kind = Node::Kind::kSignal;
        n->name = name;
        return n;
      }
      return call(name, two);
    }
    fail("expected a number, a signal, a function or '('");
  }

  NodePtr call(const std::string& name, bool two) {
    expect('(', "'(' after " + name);
    auto n = std::make_shared<Node>();
    n->kind = Node::Kind::kCall;
    n->name = name;
    n->children = {expr()};
    if (two) {
      const Parameter param = parameter_of(name);
      const std::string meaning = param.meaning;
      expect(',', "',' and " + meaning + " of " + name + "(x, " + param.letter + ")");
      skip_space();
      const std::size_t at = pos_;
      if (param.positive && at < text_.size() && text_[at] == '-') {
        fail(std::string("expected ") + param.positive);
      }
      n->number = number(meaning + " (a number)");
      if (param.positive && !(n->number > 0.0)) {
        pos_ = at;
        fail(std::string("expected ") + param.positive);
      }
    }
    expect(')', two ? "')' closing " + name + "(x, ...)" : "')' closing " + name + "(x)");
    return n;
  }

  const std::string& text_;
  std::size_t pos_ = 0;
};

int precedence(const Node& n) {
  switch (n.kind) {
    case Node::Kind::kAdd:
    case Node::Kind::kSub: return 1;
    case Node::Kind::kMul: return 2;
    case Node::Kind::kNeg: return 3;
    case Node::Kind::kPow: return 4;
    default: return 5;
  }
}

std::string print(const Node& n) {
  auto wrap = [](const Node& child, bool paren) { return paren ? "(" + print(child) + ")" : print(child); };
  switch (n.kind) {
    case Node::Kind::kNumber: return format_number(n.number);
    case Node::Kind::kSignal: return n.name;
    case Node::Kind::kAdd:
      return wrap(*n.children[0], false) + " + " + wrap(*n.children[1], precedence(*n.children[1]) <= 1);
    case Node::Kind::kSub:
      return wrap(*n.children[0], false) + " - " + wrap(*n.children[1], precedence(*n.children[1]) <= 1);
    case Node::Kind::kMul:
      return wrap(*n.children[0], precedence(*n.children[0]) < 2) + "*" +
             wrap(*n.children[1], precedence(*n.children[1]) <= 2 && n.children[1]->kind != Node::Kind::kNeg);
    case Node::Kind::kNeg: return "-" + wrap(*n.children[0], precedence(*n.children[0]) < 3);
    case Node::Kind::kPow: return wrap(*n.children[0], precedence(*n.children[0]) < 5) + "^" + std::to_string(n.power);
    case Node::Kind::kCall: {
      std::string s = n.name + "(" + print(*n.children[0]);
      if (contains(two_argument_functions(), n.name)) s += ", " + format_number(n.number);
      return s + ")";
    }
  }
  return {};
}

void collect_signals(const Node& n, std::set<std::string>& out) {
  if (n.kind == Node::Kind::kSignal) out.insert(n.name);
  for (const auto& c : n.children) collect_signals(*c, out);
}

bool has_state(const Node& n) {
  if (n.kind == Node::Kind::kCall && (n.name == "backlash" || n.name == "lag" || n.name == "ratelimit")) {
    return true;
  }
  for (const auto& c : n.children)
    if (has_state(*c)) return true;
  return false;
}

bool same(const Node& a, const Node& b) {
  if (a.kind != b.kind || a.name != b.name || a.power != b.power || a.children.size() != b.children.size())
    return false;
  if (std::memcmp(&a.number, &b.number, sizeof(double)) != 0) return false;
  for (std::size_t i = 0; i < a.children.size(); ++i)
    if (!same(*a.children[i], *b.children[i])) return false;
  return true;
}

}  // namespace

TermParseError::TermParseError(std::string text, std::size_t position, std::string problem)
    : std::invalid_argument("expression '" + text + "': at position " + std::to_string(position + 1) + ": " + problem),
      position_(position),
      problem_(std::move(problem)) {}

const std::vector<std::string>& term_signal_names() {
  static const std::vector<std::string> names{"p",   "q",     "r",       "u",       "v",       "w",
                                              "phi", "theta", "delta_f", "delta_t", "delta_d", "delta_w"};
  return names;
}

TermExpression TermExpression::parse(const std::string& text) {
  TermExpression e;
  e.root_ = Parser(text).parse();
  return e;
}

std::string TermExpression::to_string() const { return print(*root_); }

std::vector<std::string> TermExpression::signals() const {
  std::set<std::string> s;
  collect_signals(*root_, s);
  return {s.begin(), s.end()};
}

bool TermExpression::stateful() const { return has_state(*root_); }

bool TermExpression::same_as(const TermExpression& other) const { return same(*root_, *other.root_); }

TermProgram::TermProgram(const TermExpression& expression, const std::vector<std::string>& signal_order) {
  emit(expression.root(), signal_order, 0);
  stack_.assign(static_cast<std::size_t>(max_depth_) + 1, 0.0);
  pending_.assign(state_.size(), 0.0);
  started_.assign(state_.size(), 0);
}

void TermProgram::emit(const TermExpression::Node& n, const std::vector<std::string>& order, int depth) {
  max_depth_ = std::max(max_depth_, depth + 1);
  for (std::size_t i = 0; i < n.children.size(); ++i) emit(*n.children[i], order, depth + static_cast<int>(i));
  Instr in{Op::kConst};
  switch (n.kind) {
    case Node::Kind::kNumber: in = {Op::kConst, n.number, 0}; break;
    case Node::Kind::kSignal: {
      auto it = std::find(order.begin(), order.end(), n.name);
      if (it == order.end()) {
        std::string known;
        for (const auto& s : order) known += (known.empty() ? "" : ", ") + s;
        throw std::invalid_argument("unknown signal '" + n.name + "' (known: " + known + ")");
      }
      in = {Op::kSignal, 0.0, static_cast<int>(it - order.begin())};
      break;
    }
    case Node::Kind::kAdd: in = {Op::kAdd}; break;
    case Node::Kind::kSub: in = {Op::kSub}; break;
    case Node::Kind::kMul: in = {Op::kMul}; break;
    case Node::Kind::kNeg: in = {Op::kNeg}; break;
    case Node::Kind::kPow: in = {Op::kPow, 0.0, n.power}; break;
    case Node::Kind::kCall:
      if (n.name == "abs")
        in = {Op::kAbs};
      else if (n.name == "sign")
        in = {Op::kSign};
      else if (n.name == "pos")
        in = {Op::kPos};
      else if (n.name == "neg")
        in = {Op::kNeg0};
      else if (n.name == "deadzone")
        in = {Op::kDeadzone, n.number, 0};
      else if (n.name == "sat")
        in = {Op::kSat, n.number, 0};
      else {
        const Op op = n.name == "lag" ? Op::kLag : n.name == "ratelimit" ? Op::kRateLimit : Op::kBacklash;
        in = {op, n.number, static_cast<int>(state_.size())};
        state_.push_back(0.0);
      }
      break;
  }
  code_.push_back(in);
}

double TermProgram::evaluate(const double* signals) {
  double* s = stack_.data();
  int top = -1;
  for (const Instr& in : code_) {
    switch (in.op) {
      case Op::kConst: s[++top] = in.value; break;
      case Op::kSignal: s[++top] = signals[in.index]; break;
      case Op::kAdd:
        s[top - 1] += s[top];
        --top;
        break;
      case Op::kSub:
        s[top - 1] -= s[top];
        --top;
        break;
      case Op::kMul:
        s[top - 1] *= s[top];
        --top;
        break;
      case Op::kNeg: s[top] = -s[top]; break;
      case Op::kPow: {
        double base = s[top], r = 1.0;
        for (int i = 0; i < in.index; ++i) r *= base;
        s[top] = r;
        break;
      }
      case Op::kAbs: s[top] = std::fabs(s[top]); break;
      case Op::kSign: s[top] = s[top] > 0.0 ? 1.0 : (s[top] < 0.0 ? -1.0 : 0.0); break;
      case Op::kPos: s[top] = std::max(s[top], 0.0); break;
      case Op::kNeg0: s[top] = std::min(s[top], 0.0); break;
      case Op::kDeadzone: {
        double x = s[top], w = in.value;
        s[top] = x > w ? x - w : (x < -w ? x + w : 0.0);
        break;
      }
      case Op::kSat: s[top] = std::clamp(s[top], -in.value, in.value); break;
      case Op::kBacklash: {
        const auto k = static_cast<std::size_t>(in.index);
        double x = s[top], w = in.value;
        if (!started_[k]) {
          state_[k] = x;
          started_[k] = 1;
        }
        double y = std::clamp(state_[k], x - w, x + w);
        pending_[k] = y;
        s[top] = y;
        break;
      }
      case Op::kLag: {
        const auto k = static_cast<std::size_t>(in.index);
        double x = s[top];
        if (!started_[k]) {
          state_[k] = x;
          started_[k] = 1;
        }
        pending_[k] = x;
        s[top] = state_[k];
        break;
      }
      case Op::kRateLimit: {
        // The input, within the reach of the last committed output over the last step.
        const auto k = static_cast<std::size_t>(in.index);
        double x = s[top];
        if (!started_[k]) {
          state_[k] = x;
          started_[k] = 1;
        }
        const double reach = in.value * dt_s_;
        double y = std::min(std::max(x, state_[k] - reach), state_[k] + reach);
        pending_[k] = y;
        s[top] = y;
        break;
      }
    }
  }
  return s[0];
}

void TermProgram::advance(double dt_s) {
  for (const Instr& in : code_) {
    if (in.op == Op::kBacklash || in.op == Op::kRateLimit) {
      state_[static_cast<std::size_t>(in.index)] = pending_[static_cast<std::size_t>(in.index)];
    } else if (in.op == Op::kLag) {
      const auto k = static_cast<std::size_t>(in.index);
      state_[k] = pending_[k] + (state_[k] - pending_[k]) * std::exp(-dt_s / in.value);
    }
  }
  dt_s_ = dt_s;
}

void TermProgram::reset() {
  std::fill(started_.begin(), started_.end(), 0);
  std::fill(state_.begin(), state_.end(), 0.0);
  dt_s_ = 0.0;
}

std::vector<double> evaluate_along(const TermExpression& expression, const std::vector<std::string>& names,
                                   const std::vector<const std::vector<double>*>& columns, double dt_s) {
  if (names.size() != columns.size()) throw std::invalid_argument("evaluate_along: names and columns differ in number");
  TermProgram program(expression, names);
  std::size_t n = columns.empty() ? 0 : columns[0]->size();
  for (const auto* c : columns)
    if (c->size() != n) throw std::invalid_argument("evaluate_along: columns differ in length");
  std::vector<double> row(columns.size()), out(n);
  for (std::size_t k = 0; k < n; ++k) {
    for (std::size_t j = 0; j < columns.size(); ++j) row[j] = (*columns[j])[k];
    out[k] = program.evaluate(row.data());
    program.advance(dt_s);
  }
  return out;
}

}  // namespace nimble
