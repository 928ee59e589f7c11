// `rig reproduce thesis --beside` (reproduce/beside.h): how a cell moved between the run without
// the overrides and the run with them, and the two runs' tables merged, on synthetic cells.

#include <catch2/catch.hpp>
#include <nlohmann/json.hpp>

#include <cmath>

#include "reproduce/beside.h"

using namespace nimble::reproduce;

namespace {

Cell cell(double published, double rig, double interval, double tolerance, const std::string& verdict = "differs",
          const std::string& row = "p", const std::string& column = "R2") {
  Cell c;
  c.row = row;
  c.column = column;
  c.published = published;
  c.reference = published;
  c.rig = rig;
  c.interval = interval;
  c.tolerance = tolerance;
  c.category = "flights";
  c.verdict = verdict;
  return c;
}

CampaignResult run(const std::vector<Cell>& cells, const std::vector<std::string>& overrides = {}) {
  CampaignResult r;
  r.clock = "inprocess";
  r.seeds = {1, 2};
  r.states = "smoothed";
  r.overrides = overrides;
  Table t;
  t.id = "9.4";
  t.title = "ranges";
  t.category = "flights";
  t.cells = cells;
  r.tables = {t};
  return r;
}

}  // namespace

TEST_CASE(
    "beside: a cell moves toward or away by its distance to the published value, the same within its "
    "tolerance or interval",
    "[beside]") {
  // Published 1, tolerance 0.1: from 2 to 1.5 is toward, to 2.5 away; a crossing to 0 is the same
  // distance, so the same.
  CHECK(moved(cell(1, 2, 0, 0.1), cell(1, 1.5, 0, 0.1)) == "toward");
  CHECK(moved(cell(1, 2, 0, 0.1), cell(1, 2.5, 0, 0.1)) == "away");
  CHECK(moved(cell(1, 2, 0, 0.1), cell(1, 0, 0, 0.1)) == "same");
  // Within the tolerance: the same, whichever way.
  CHECK(moved(cell(1, 2, 0, 0.1), cell(1, 1.95, 0, 0.1)) == "same");
  CHECK(moved(cell(1, 2, 0, 0.1), cell(1, 2.08, 0, 0.1)) == "same");
  // Within the two means' interval (0.3 and 0.4 in quadrature: 0.5) though beyond the tolerance.
  CHECK(moved(cell(1, 2, 0.3, 0.1), cell(1, 1.55, 0.4, 0.1)) == "same");
  CHECK(moved(cell(1, 2, 0.3, 0.1), cell(1, 1.45, 0.4, 0.1)) == "toward");
  // A pipeline check moves against the plant file's value, not the thesis's.
  Cell a = cell(1, 2, 0, 0.1), b = cell(1, 2.5, 0, 0.1);
  a.reference = b.reference = 3;
  CHECK(moved(a, b) == "toward");
  // No value in a run: nothing to say.
  CHECK(moved(cell(1, NAN, 0, 0.1), cell(1, 1.5, 0, 0.1)) == "n/a");
  CHECK(moved(cell(1, 2, 0, 0.1), cell(1, NAN, 0, 0.1)) == "n/a");
}

TEST_CASE("beside: the merge keeps each run's verdicts as judged and counts moves and verdict changes", "[beside]") {
  std::vector<Cell> a{cell(1, 2, 0, 0.1, "differs", "p"), cell(1, 1.05, 0, 0.1, "match", "v"),
                      cell(1, 1.05, 0, 0.1, "match", "phi")};
  std::vector<Cell> b{cell(1, 1.5, 0, 0.1, "differs", "p"), cell(1, 1.6, 0, 0.1, "differs", "v"),
                      cell(1, 1.05, 0, 0.1, "match", "phi")};
  // The third cell repeats an earlier one in both runs: shown, counted once (here: not at all).
  a[2].repeats = b[2].repeats = "9.4 / v / R2";
  const BesideResult r = merge_beside(run(a), run(b, {"sensing.base=/x.yaml"}));
  REQUIRE(r.tables.size() == 1);
  REQUIRE(r.tables[0].cells.size() == 3);
  // An honest differs stays differs: moving toward the published value changes no verdict.
  CHECK(r.tables[0].cells[0].without.verdict == "differs");
  CHECK(r.tables[0].cells[0].with.verdict == "differs");
  CHECK(r.tables[0].cells[0].moved == "toward");
  CHECK(r.tables[0].cells[1].moved == "away");
  const auto moves = r.moved_counts().at("flights");
  CHECK(moves.at("toward") == 1);
  CHECK(moves.at("away") == 1);
  CHECK(moves.count("same") == 0);
  CHECK(r.verdict_changes().at("flights").at("match -> differs") == 1);
  CHECK(r.verdict_changes().at("flights").size() == 1);

  const std::string text = beside_text(r);
  CHECK_THAT(text, Catch::Contains("overrides (every flight of the second run): sensing.base=/x.yaml"));
  CHECK_THAT(text, Catch::Contains("1 toward, 1 away (of 2)"));
  CHECK_THAT(text, Catch::Contains("verdicts changed: 1 match -> differs (of 1)"));
  CHECK_THAT(text, Catch::Contains("(repeats 9.4 / v / R2)"));

  const auto j = nlohmann::json::parse(beside_json(r));
  const auto& c = j.at("tables").at(0).at("cells").at(0);
  CHECK(c.at("rig_without").get<double>() == 2.0);
  CHECK(c.at("rig_with").get<double>() == 1.5);
  CHECK(c.at("moved") == "toward");
  CHECK(c.at("verdict_with") == "differs");
  CHECK(c.at("with").at("verdict") == "differs");
  CHECK(j.at("with").at("overrides").at(0) == "sensing.base=/x.yaml");
  CHECK(j.at("without").at("overrides").empty());
  CHECK(j.at("moved").at("flights").at("toward") == 1);

  // Runs whose cells do not line up are refused.
  std::vector<Cell> other = b;
  other[1].row = "w";
  CHECK_THROWS_WITH(merge_beside(run(a), run(other)), Catch::Contains("beside"));
}

TEST_CASE("beside: without overrides there is nothing to fly beside", "[beside]") {
  CampaignOptions o;
  CHECK_THROWS_WITH(run_beside(o), Catch::Contains("--beside needs overrides"));
}
