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
  r.max_off = 0.2;
  r.states = {"smoothed"};
  t.reasons = {r};
  const Cell ok = judge(t, "p_dot", "R2", {0.99}, ctx());
  CHECK(ok.verdict == "explained");
  CHECK(ok.has_check);
  CHECK(ok.check.holds);
  // The wrong direction, too large a difference, other states: each makes the cell differ.
  const Cell below = judge(t, "p_dot", "R2", {0.80}, ctx());
  CHECK(below.verdict == "differs");
  CHECK_FALSE(below.check.holds);
  CHECK_THAT(below.reason, Catch::Contains("check fails"));
  t.reasons[0].max_off = 0.05;
  CHECK(judge(t, "p_dot", "R2", {0.99}, ctx()).verdict == "differs");
  t.reasons[0].max_off = 0.2;
  CHECK(judge(t, "p_dot", "R2", {0.99}, ctx("estimate")).verdict == "differs");
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

TEST_CASE("verdict: calibrated and model cells match or differ, and not comparable cells carry no verdict", "[verdict]") {
  for (const Category c : {Category::kCalibrated, Category::kModel}) {
    CHECK(judge(table(c), "p_dot", "R2", {0.92}, ctx()).verdict == "match");
    CHECK(judge(table(c), "p_dot", "R2", {0.99}, ctx()).verdict == "differs");
  }
  const Cell nc = judge(table(Category::kNotComparable), "p_dot", "R2", {0.99}, ctx());
  CHECK(nc.verdict == "not comparable");
  CHECK(nc.rig == Approx(0.99));
  CHECK(nc.reason == "why");
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
  t.reasons = {r};
  const Cell tuned = judge(t, "p_dot", "R2", {0.99}, ctx());
  CHECK(tuned.category == "calibrated");
  CHECK(tuned.verdict == "differs");  // a calibrated cell is never explained
  CHECK(judge(t, "p_dot", "R2", {0.91}, ctx()).reason == "tuned");
  const Cell held_out = judge(t, "p_dot", "rxy", {0.999}, ctx());
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
