// Unit tests of the term grammar (core/term_expression.h): parsing, errors, printing, evaluation.

#include <algorithm>
#include <cmath>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "core/term_expression.h"

using namespace nimble;

namespace {

std::string parse_error(const std::string& text) {
  try {
    TermExpression::parse(text);
  } catch (const TermParseError& e) {
    return e.what();
  }
  return "(parsed)";
}

double value_at(const std::string& text, const std::vector<std::string>& names, const std::vector<double>& x) {
  TermProgram program(TermExpression::parse(text), names);
  return program.evaluate(x.data());
}

}  // namespace

TEST_CASE("term expressions parse, print and round-trip", "[term]") {
  const std::vector<std::string> good{"p^3",
                                      "v*abs(v)",
                                      "pos(delta_f)",
                                      "deadzone(delta_f, 0.05)",
                                      "lag(delta_f, 0.02)",
                                      "p*v^2",
                                      "-0.0005*p^3",
                                      "p - (v - phi)",
                                      "-(p*v)",
                                      "(p + v)^2",
                                      "sign(p)*neg(v) + 1e-3",
                                      "backlash(delta_f, 0.1)",
                                      "p*-v",
                                      "(-p)^3",
                                      "lag(abs(delta_f) - 2, 0.125)",
                                      "0.1 + 0.2",
                                      "sat(p, 0.5)",
                                      "ratelimit(delta_f, 300) - delta_f",
                                      "sat(ratelimit(v, 2.5), 1e-3)^2"};
  for (const auto& text : good) {
    INFO(text);
    TermExpression e = TermExpression::parse(text);
    TermExpression back = TermExpression::parse(e.to_string());
    CHECK(back.same_as(e));
    CHECK(back.to_string() == e.to_string());
  }
  CHECK(TermExpression::parse("  v *abs( v )").to_string() == "v*abs(v)");
  CHECK(TermExpression::parse("p - (v - phi)").to_string() == "p - (v - phi)");
  CHECK(TermExpression::parse("0.1 + 0.2").to_string() == "0.1 + 0.2");
  CHECK_FALSE(TermExpression::parse("p - v - phi").same_as(TermExpression::parse("p - (v - phi)")));
  CHECK(TermExpression::parse("p*v^2 + lag(delta_f, 0.02)").signals() == std::vector<std::string>{"delta_f", "p", "v"});
  CHECK(TermExpression::parse("lag(delta_f, 0.02)").stateful());
  CHECK_FALSE(TermExpression::parse("deadzone(delta_f, 0.02)").stateful());
  CHECK(TermExpression::parse(" ratelimit( delta_f,2.5 )").to_string() == "ratelimit(delta_f, 2.5)");
  CHECK(TermExpression::parse("sat(p,0.25)").to_string() == "sat(p, 0.25)");
  CHECK(TermExpression::parse("ratelimit(delta_f, 300)").stateful());
  CHECK(TermExpression::parse("sat(lag(p, 0.1), 1)").stateful());
  CHECK_FALSE(TermExpression::parse("sat(delta_f, 3)").stateful());
  CHECK(TermExpression::parse("sat(v, 1)*ratelimit(delta_f, 300)").signals() ==
        std::vector<std::string>{"delta_f", "v"});
  CHECK_FALSE(TermExpression::parse("sat(p, 2)").same_as(TermExpression::parse("ratelimit(p, 2)")));
}

TEST_CASE("bad term expressions are refused naming the position and what was expected", "[term]") {
  CHECK(parse_error("p^") ==
        "expression 'p^': at position 3: expected an integer power in [0, 16] after '^', found the end");
  CHECK(parse_error("p^1.5") == "expression 'p^1.5': at position 3: expected an integer power in [0, 16], found '1.5'");
  CHECK(parse_error("p +* v") ==
        "expression 'p +* v': at position 4: expected a number, a signal, a function or '(', found '*'");
  CHECK(parse_error("abs(p") == "expression 'abs(p': at position 6: expected ')' closing abs(x), found the end");
  CHECK(parse_error("lag(delta_f)") ==
        "expression 'lag(delta_f)': at position 12: expected ',' and the time constant tau [s] of lag(x, tau), found "
        "')'");
  CHECK(parse_error("lag(delta_f, 0)") ==
        "expression 'lag(delta_f, 0)': at position 14: expected a time constant tau > 0 s, found '0'");
  CHECK(parse_error("deadzone(p, v)") ==
        "expression 'deadzone(p, v)': at position 13: expected the width w (a number), found 'v'");
  CHECK(parse_error("p v") ==
        "expression 'p v': at position 3: expected an operator (+, -, *, ^) or the end of the expression, found 'v'");
  CHECK(parse_error("2p") == "expression '2p': at position 2: expected an operator after the number 2, found 'p'");
  CHECK(parse_error("") ==
        "expression '': at position 1: expected a number, a signal, a function or '(', found the end");
  CHECK(parse_error("p / v") ==
        "expression 'p / v': at position 3: expected an operator (+, -, *, ^) or the end of the expression, found '/'");
  // A signal outside the order a program is bound to is refused naming it.
  try {
    TermProgram program(TermExpression::parse("p*x"), {"p", "v"});
    FAIL("bound");
  } catch (const std::invalid_argument& e) {
    CHECK(std::string(e.what()) == "unknown signal 'x' (known: p, v)");
  }
}

TEST_CASE("term evaluation matches hand-computed values", "[term]") {
  const std::vector<std::string> names{"p", "v", "delta_f"};
  const std::vector<double> x{-2.0, 0.5, 0.03};
  CHECK(value_at("p^3", names, x) == -8.0);
  CHECK(value_at("-0.0005*p^3", names, x) == Approx(0.004));
  CHECK(value_at("v*abs(v)", names, x) == 0.25);
  CHECK(value_at("p*v^2", names, x) == -0.5);
  CHECK(value_at("p - (v - 1)", names, x) == -1.5);
  CHECK(value_at("pos(p) + neg(p) + sign(p)", names, x) == -3.0);
  CHECK(value_at("p^0", names, x) == 1.0);
  CHECK(value_at("deadzone(delta_f, 0.05)", names, x) == 0.0);
  CHECK(value_at("deadzone(p, 0.5)", names, x) == -1.5);
  CHECK(value_at("deadzone(v, 0.2)", names, x) == Approx(0.3));

  // lag: starts at its input, then y(t) = x + (y0 - x) exp(-t/tau) for an input held over the step.
  {
    TermProgram lag(TermExpression::parse("lag(p, 0.02)"), {"p"});
    double in0 = 0.0, in1 = 1.0;
    CHECK(lag.evaluate(&in0) == 0.0);
    lag.advance(0.01);
    CHECK(lag.evaluate(&in1) == 0.0);  // the step held 0
    lag.advance(0.01);
    CHECK(lag.evaluate(&in1) == Approx(1.0 - std::exp(-0.5)).epsilon(1e-14));
    lag.advance(0.02);
    CHECK(lag.evaluate(&in1) == Approx(1.0 - std::exp(-1.5)).epsilon(1e-14));
    lag.reset();
    CHECK(lag.evaluate(&in1) == 1.0);
  }
  // backlash of half-width 0.1: 0 -> 0.5 (follows at 0.4) -> 0.45 (stays) -> 0.2 (follows at 0.3).
  {
    TermProgram b(TermExpression::parse("backlash(delta_f, 0.1)"), {"delta_f"});
    const std::vector<double> in{0.0, 0.5, 0.45, 0.2};
    const std::vector<double> out{0.0, 0.4, 0.4, 0.3};
    for (std::size_t k = 0; k < in.size(); ++k) {
      CHECK(b.evaluate(&in[k]) == Approx(out[k]));
      b.advance(0.002);
    }
  }
  // Along a record: the same values sample by sample.
  const std::vector<double> p{0.0, 1.0, 1.0};
  auto along = evaluate_along(TermExpression::parse("lag(p, 0.02) + p^2"), {"p"}, {&p}, 0.01);
  REQUIRE(along.size() == 3);
  CHECK(along[0] == 0.0);
  CHECK(along[1] == 1.0);
  CHECK(along[2] == Approx(1.0 + 1.0 - std::exp(-0.5)));
}

TEST_CASE("sat and ratelimit refuse a missing or non-positive argument naming it", "[term]") {
  CHECK(parse_error("sat(p, 0)") == "expression 'sat(p, 0)': at position 8: expected a limit s > 0, found '0'");
  CHECK(parse_error("sat(p, -1)") == "expression 'sat(p, -1)': at position 8: expected a limit s > 0, found '-1'");
  CHECK(parse_error("sat(p)") ==
        "expression 'sat(p)': at position 6: expected ',' and the limit s of sat(x, s), found ')'");
  CHECK(parse_error("sat(p, )") == "expression 'sat(p, )': at position 8: expected the limit s (a number), found ')'");
  CHECK(parse_error("ratelimit(p, 0)") ==
        "expression 'ratelimit(p, 0)': at position 14: expected a rate r > 0 per second, found '0'");
  CHECK(parse_error("ratelimit(p, -300)") ==
        "expression 'ratelimit(p, -300)': at position 14: expected a rate r > 0 per second, found '-300'");
  CHECK(parse_error("ratelimit(p)") ==
        "expression 'ratelimit(p)': at position 12: expected ',' and the rate r [per s] of ratelimit(x, r), found ')'");
}

namespace {

/// Samples of `text` along x (bound to the one signal p), stepping a program by dt.
std::vector<double> stepped(const std::string& text, const std::vector<double>& x, double dt) {
  TermProgram program(TermExpression::parse(text), {"p"});
  std::vector<double> y;
  for (double in : x) {
    y.push_back(program.evaluate(&in));
    program.advance(dt);
  }
  return y;
}

std::vector<double> sine(double amplitude, double hz, double dt, int n) {
  std::vector<double> x(static_cast<std::size_t>(n));
  for (int k = 0; k < n; ++k) x[static_cast<std::size_t>(k)] = amplitude * std::sin(2.0 * M_PI * hz * k * dt);
  return x;
}

}  // namespace

TEST_CASE("sat limits the amplitude, ratelimit follows its input as closely as the rate allows", "[term]") {
  const std::vector<std::string> names{"p", "v"};
  CHECK(value_at("sat(p, 0.5)", names, {-2.0, 0.0}) == -0.5);
  CHECK(value_at("sat(p, 0.5)", names, {0.75, 0.0}) == 0.5);
  CHECK(value_at("sat(v, 1)", names, {0.0, 0.3}) == 0.3);
  CHECK(value_at("sat(p - v, 2)", names, {1.0, -0.5}) == 1.5);

  const double dt = 0.01, r = 2.0;  // 0.02 per sample
  // A step from 0 to 1, then to -0.5: followed at r, the input reached and then held exactly.
  {
    std::vector<double> x(60, 1.0);
    x[0] = 0.0;
    x.insert(x.end(), 100, -0.5);
    const auto y = stepped("ratelimit(p, 2)", x, dt);
    CHECK(y[0] == 0.0);
    CHECK(y[1] == Approx(0.02).margin(1e-12));
    CHECK(y[25] == Approx(0.5).margin(1e-12));
    CHECK(y[49] == Approx(0.98).margin(1e-12));
    CHECK(y[50] == 1.0);
    CHECK(y[59] == 1.0);
    CHECK(y[60] == Approx(0.98).margin(1e-12));
    CHECK(y[60 + 74] == Approx(1.0 - 75 * 0.02).margin(1e-12));
    CHECK(y.back() == -0.5);
  }
  // A sine slower than r (peak rate 2 pi 0.25 = 1.57 per s) passes unchanged, sample for sample.
  {
    const auto x = sine(1.0, 0.25, dt, 400);
    const auto y = stepped("ratelimit(p, 2)", x, dt);
    std::size_t differ = 0;
    for (std::size_t k = 0; k < x.size(); ++k) differ += y[k] != x[k];
    CHECK(differ == 0);
  }
  // A faster one (peak rate 2 pi = 6.3 per s) is limited: its rate never above r, and at r where limited.
  const auto fast = sine(1.0, 1.0, dt, 300);
  const auto y = stepped("ratelimit(p, 2)", fast, dt);
  double max_rate = 0.0, max_gap = 0.0;
  for (std::size_t k = 1; k < y.size(); ++k) {
    max_rate = std::max(max_rate, std::fabs(y[k] - y[k - 1]) / dt);
    max_gap = std::max(max_gap, std::fabs(y[k] - fast[k]));
  }
  CHECK(max_rate <= r * (1.0 + 1e-12));
  CHECK(max_rate >= r * (1.0 - 1e-12));
  CHECK(max_gap > 0.3);

  // The same values along a record, and as a plain rate limiter computes them.
  const std::vector<double> along = evaluate_along(TermExpression::parse("ratelimit(p, 2)"), {"p"}, {&fast}, dt);
  CHECK(along == y);
  double held = fast[0];
  std::size_t differ = 0;
  for (std::size_t k = 0; k < fast.size(); ++k) {
    held = std::clamp(fast[k], held - r * dt, held + r * dt);
    differ += held != y[k];
  }
  CHECK(differ == 0);

  // reset() forgets the state: the next evaluate starts at the input.
  TermProgram program(TermExpression::parse("ratelimit(p, 2)"), {"p"});
  double zero = 0.0, one = 1.0;
  program.evaluate(&zero);
  program.advance(dt);
  CHECK(program.evaluate(&one) == Approx(0.02));
  program.reset();
  CHECK(program.evaluate(&one) == 1.0);
  CHECK(program.evaluate(&zero) == 1.0);  // no step since the start: the output has not moved
  program.advance(dt);
  CHECK(program.evaluate(&zero) == Approx(0.98));
}
