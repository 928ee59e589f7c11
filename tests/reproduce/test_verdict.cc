// The verdict rules of `rig reproduce thesis` (reproduce/cell_verdict.h): every cell can fail, and a
// reason explains a cell only while its predicate holds in the same run.

#include <catch2/catch.hpp>

#include "reproduce/cell_verdict.h"

using namespace nimble::reproduce;

namespace {

TableSpec table(Category category = Category::kFlights) {
  TableSpec t;
  t.category = category;
  t.why = "why";
  t.relative = 0.05;
  t.published["p_dot"]["R2"] = 0.90;
  t.printed_half_digit["p_dot"]["R2"] = 0.005;  // printed "0.90"
  t.row_order = {"p_dot"};
  t.column_order["p_dot"] = {"R2"};
  return t;
}

JudgeContext ctx(const std::string& states = "smoothed") {
  JudgeContext c;
  c.states = states;
  return c;
}

}  // namespace

TEST_CASE("verdict: within the tolerance a match, outside it without a reason differs", "[verdict]") {
  const TableSpec t = table();
  CHECK(judge(t, "p_dot", "R2", {0.92}, ctx()).verdict == "match");
  const Cell c = judge(t, "p_dot", "R2", {0.99}, ctx());
  CHECK(c.verdict == "differs");
  CHECK(c.tolerance == Approx(0.045));
}

TEST_CASE("verdict: a reason explains only while each part of its predicate holds", "[verdict]") {
  TableSpec t = table();
  Reason r;
  r.cells = {"p_dot / R2"};
  r.text = "the plant lacks the flapping dynamics";
  r.rig = "above";
  r.max_off = 0.12;  // the gap is 0.09: within 1.5 times it
  r.states = {"smoothed"};
  r.with = {{"plant.effects.flapping_forcing.enabled", "true"}};
  t.reasons = {r};
  JudgeContext c = ctx();
  c.with_values = {0.93};  // the cause takes the cell 0.09 -> 0.03 from the published value
  const Cell ok = judge(t, "p_dot", "R2", {0.99}, c);
  CHECK(ok.verdict == "explained");
  CHECK(ok.has_check);
  CHECK(ok.check.holds);
  // The wrong direction, too large a difference, other states: each makes the cell differ.
  const Cell below = judge(t, "p_dot", "R2", {0.80}, c);
  CHECK(below.verdict == "differs");
  CHECK_FALSE(below.check.holds);
  CHECK_THAT(below.reason, Catch::Contains("check fails"));
  t.reasons[0].max_off = 0.05;
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "differs");
  t.reasons[0].max_off = 0.12;
  c.states = "estimate";
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "differs");
}

TEST_CASE(
    "verdict: direction, bound and states describe a difference: without a cause flown they do not explain it, "
    "and a bound that cannot fail is refused",
    "[verdict]") {
  TableSpec t = table();
  Reason r;
  r.cells = {"p_dot / R2"};
  r.text = "describes only";
  r.rig = "above";
  r.max_off = 0.12;
  r.states = {"smoothed", "estimate", "truth"};
  t.reasons = {r};
  const Cell no_cause = judge(t, "p_dot", "R2", {0.99}, ctx());
  CHECK(no_cause.verdict == "differs");
  CHECK_THAT(no_cause.check.value, Catch::Contains("names no cause"));
  // The vacuous reason: any direction's bound of 1e9, every state source, a cause that moves the
  // cell all the way: the bound alone makes it fail.
  t.reasons[0].max_off = 1e9;
  t.reasons[0].with = {{"plant.effects.flapping_forcing.enabled", "true"}};
  JudgeContext c = ctx();
  c.with_values = {0.90};
  const Cell vacuous = judge(t, "p_dot", "R2", {0.99}, c);
  CHECK(vacuous.verdict == "differs");
  CHECK_THAT(vacuous.check.value, Catch::Contains("cannot fail"));
  t.reasons[0].max_off = 1.5 * 0.09 * 0.999;  // just inside 1.5 times the gap
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "explained");
}

TEST_CASE(
    "verdict: by equivalence, an interval inside the band matches, wholly outside differs, across an edge is "
    "inconclusive with the seeds that would decide it",
    "[verdict]") {
  // Table 9.6's Yv+ with the published value moved to -1.5: the rig's -1.137 +- 0.015 lies wholly
  // outside the band (2 thesis sigma, 6.7e-4 each, raised to the 0.005 of the printed -1.13) and
  // differs, though its interval is wider than the tolerance.
  TableSpec t;
  t.category = Category::kFlights;
  t.thesis_sigmas = 2;
  t.thesis_sigma["set 1 / Yv+"] = 6.7e-4;
  t.published["set 1"]["Yv+"] = -1.5;
  t.printed_half_digit["set 1"]["Yv+"] = 0.005;                           // written "-1.50"
  const std::vector<double> rig{-1.152, -1.122, -1.142, -1.127, -1.142};  // -1.137 +- 0.015
  const Cell moved = judge(t, "set 1", "Yv+", rig, ctx());
  CHECK(moved.interval > moved.tolerance);
  CHECK(moved.verdict == "differs");
  t.published["set 1"]["Yv+"] = -1.13;
  const Cell near = judge(t, "set 1", "Yv+", rig, ctx());
  CHECK(near.verdict == "inconclusive");
  CHECK(near.seeds_to_decide > 5);
  CHECK_THAT(near.reason, Catch::Contains("seeds would decide it"));
  // A relative band of 5 %: the same seeds inside it match.
  TableSpec wide = table();
  CHECK(judge(wide, "p_dot", "R2", {0.91, 0.92, 0.90}, ctx()).verdict == "match");
  // Straddling the upper edge 0.945: inconclusive, and more seeds of the same spread decide it.
  const Cell edge = judge(wide, "p_dot", "R2", {0.93, 0.96, 0.95}, ctx());
  CHECK(edge.verdict == "inconclusive");
  CHECK(edge.seeds_to_decide > 3);
  // Wholly above the band: differs.
  CHECK(judge(wide, "p_dot", "R2", {0.99, 0.995, 0.985}, ctx()).verdict == "differs");
}

TEST_CASE("verdict: the seeds that decide an interval come from Student's t", "[verdict]") {
  // sd 1, distance 1: t(n-1) / sqrt(n) < 1 first at n = 7 (2.447 / 2.646 = 0.925; n = 6: 2.571 /
  // 2.449 = 1.05).
  CHECK(seeds_to_decide(1.0, 1.0) == 7);
  CHECK(seeds_to_decide(1.0, 0.0) == 0);
  CHECK(seeds_to_decide(0.0, 0.5) == 2);
  CHECK(seeds_to_decide(1.0, 0.1) > 380);  // about (1.96 / 0.1)^2 = 384
}

TEST_CASE("verdict: a reason naming a cause holds only if the flight with the cause moves the cell", "[verdict]") {
  TableSpec t = table();
  Reason r;
  r.cells = {"p_dot / R2"};
  r.text = "flapping";
  r.with = {{"plant.effects.flapping_forcing.enabled", "true"}};
  r.at_least = 0.25;
  t.reasons = {r};
  JudgeContext c = ctx();
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "differs");  // not flown
  c.with_values = {0.95};                                          // 0.09 -> 0.05: 44 % of the gap
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "explained");
  c.with_values = {0.98};  // 11 %: too little
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "differs");
  c.with_values = {1.00};  // away
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "differs");
}

TEST_CASE("verdict: the rig's noise never widens a tolerance, and too noisy is inconclusive", "[verdict]") {
  TableSpec t = table();
  t.thesis_sigma["p_dot / R2"] = 0.01;
  t.thesis_sigmas = 2;
  const Cell quiet = judge(t, "p_dot", "R2", {0.915, 0.916, 0.914}, ctx());
  CHECK(quiet.tolerance == Approx(0.02));
  CHECK(quiet.verdict == "match");
  const Cell noisy = judge(t, "p_dot", "R2", {0.80, 1.00, 0.90}, ctx());
  CHECK(noisy.tolerance == Approx(0.02));
  CHECK(noisy.verdict == "inconclusive");
  t.min_seeds = 5;
  CHECK(judge(t, "p_dot", "R2", {0.90, 0.90}, ctx()).verdict == "inconclusive");
}

TEST_CASE("verdict: calibrated and model cells match or differ", "[verdict]") {
  for (const Category c : {Category::kCalibrated, Category::kModel}) {
    CHECK(judge(table(c), "p_dot", "R2", {0.92}, ctx()).verdict == "match");
    CHECK(judge(table(c), "p_dot", "R2", {0.99}, ctx()).verdict == "differs");
  }
}

TEST_CASE(
    "verdict: a pipeline check is judged against the plant file's value within half the published number's "
    "last digit, on at least two seeds",
    "[verdict]") {
  // Table 9.6's Yv+: the thesis prints -1.13, the plant file's exact value is -1.1285.
  TableSpec t;
  t.category = Category::kModel;
  t.reference_table = "9.6-model";
  t.relative = 0.5;  // a table's own tolerance is not a pipeline check's
  t.published["set 1"]["Yv+"] = -1.13;
  t.printed_half_digit["set 1"]["Yv+"] = 0.005;
  JudgeContext c = ctx();
  c.reference = -1.1285;
  const Cell exact = judge(t, "set 1", "Yv+", {-1.1283, -1.1287, -1.1285}, c);
  CHECK(exact.verdict == "match");
  CHECK(exact.reference == -1.1285);
  CHECK(exact.tolerance == Approx(0.005));
  CHECK_THAT(exact.tolerance_basis, Catch::Contains("pipeline"));
  // 1 % off the plant, though within 0.5 % of the thesis's -1.13 had it been judged against it.
  const Cell biased = judge(t, "set 1", "Yv+", {-1.1399, -1.1401, -1.1400}, c);
  CHECK(biased.verdict == "differs");
  CHECK_THAT(biased.reason, Catch::Contains("plant file"));
  // Scattered around the plant's value more than the band: more seeds would decide it.
  const Cell noisy = judge(t, "set 1", "Yv+", {-1.11, -1.15, -1.13, -1.12, -1.14}, c);
  CHECK(noisy.verdict == "inconclusive");
  CHECK(noisy.seeds_to_decide > 5);
  // One seed has no interval; no plant value, no check.
  CHECK(judge(t, "set 1", "Yv+", {-1.1285}, c).verdict == "inconclusive");
  const Cell none = judge(t, "set 1", "Yv+", {-1.1285, -1.1285}, ctx());
  CHECK(none.verdict == "differs");
  CHECK_THAT(none.reason, Catch::Contains("plant file gives no value"));
}

TEST_CASE("verdict: a tuned cell of a flights table is calibrated, the cells held out are judged", "[verdict]") {
  TableSpec t = table();
  t.published["p_dot"]["rxy"] = 0.95;
  t.calibrated_cells = {"p_dot / R2"};
  t.calibrated_why = "tuned";
  Reason r;
  r.cells = {"p_dot / R2", "p_dot / rxy"};
  r.text = "would explain";
  r.rig = "above";
  r.with = {{"plant.effects.flapping_forcing.enabled", "true"}};
  t.reasons = {r};
  JudgeContext c = ctx();
  c.with_values = {0.95};
  const Cell tuned = judge(t, "p_dot", "R2", {0.99}, c);
  CHECK(tuned.category == "calibrated");
  CHECK(tuned.verdict == "differs");  // a calibrated cell is never explained
  CHECK(judge(t, "p_dot", "R2", {0.91}, c).reason == "tuned");
  const Cell held_out = judge(t, "p_dot", "rxy", {0.999}, c);
  CHECK(held_out.category == "flights");
  CHECK(held_out.verdict == "explained");
}

TEST_CASE("verdict: a cause whose flight did not fly as asked explains nothing", "[verdict]") {
  TableSpec t = table();
  Reason r;
  r.cells = {"p_dot / R2"};
  r.text = "vibration";
  r.with = {{"sensing.imu.vibration_enabled", "true"}};
  t.reasons = {r};
  JudgeContext c = ctx();
  c.with_values = {0.90};  // all the way to the published value
  CHECK(judge(t, "p_dot", "R2", {0.99}, c).verdict == "explained");
  c.with_failure = "ol_doublet_with_1 seed 1: completed in failsafe";
  const Cell failed = judge(t, "p_dot", "R2", {0.99}, c);
  CHECK(failed.verdict == "differs");
  CHECK_THAT(failed.check.value, Catch::Contains("failsafe"));
}

TEST_CASE(
    "verdict: no tolerance is tighter than the published number's rounding, and one as wide as the value "
    "judges nothing",
    "[verdict]") {
  CHECK(half_last_digit(0.24) == Approx(0.005));
  CHECK(half_last_digit(-1.13) == Approx(0.005));
  CHECK(half_last_digit(0.907) == Approx(0.0005));
  CHECK(half_last_digit(12.0) == Approx(0.5));
  // A small derivative's last digit is its own (Table D.1's N_df), not that of the units.
  CHECK(half_last_digit(-1.44e-7) == Approx(5e-10));
  CHECK(half_last_digit(8.04e-6) == Approx(5e-9));
  // Table 9.6's Yv+: 2 thesis sigma is 0.0013, under the 0.005 of the printed -1.13; the plant's
  // exact -1.1285 (truth states) matches within the rounding.
  TableSpec t;
  t.category = Category::kFlights;
  t.thesis_sigmas = 2;
  t.thesis_sigma["set 1 / Yv+"] = 6.7e-4;
  t.thesis_sigma["set 1 / Lp+"] = 0.195;
  t.published["set 1"]["Yv+"] = -1.13;
  t.published["set 1"]["Lp+"] = -0.28;
  const Cell yv = judge(t, "set 1", "Yv+", {-1.1285}, ctx("truth"));
  CHECK(yv.tolerance == Approx(0.005));
  CHECK_THAT(yv.tolerance_basis, Catch::Contains("half the printed last digit"));
  CHECK(yv.verdict == "match");
  CHECK(judge(t, "set 1", "Yv+", {-1.1385}, ctx("truth")).verdict == "differs");
  // Lp+: 2 thesis sigma is 0.39, wider than the value 0.28: no verdict, and why.
  const Cell lp = judge(t, "set 1", "Lp+", {-0.28}, ctx("truth"));
  CHECK(lp.verdict == "not judged");
  CHECK_THAT(lp.reason, Catch::Contains("as wide as the value"));
}
