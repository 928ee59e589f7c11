#pragma once
/// `rig reproduce thesis --beside`: the campaign flown twice, without and with overrides on every
/// flight (CampaignOptions::overrides, e.g. the vehicle's flight vibration), and every table's
/// cells set side by side: the published value, the rig's value without and with, each judged on
/// its own run exactly as a campaign alone judges it (reproduce/cell_verdict.h), and whether the
/// cell moved toward the published value or away.
///
/// Moved, by the distance |rig - reference| of the two runs' means (the reference is what the
/// cell is judged against: the published value, or the plant file's for a pipeline check):
/// `toward` (smaller with the overrides), `away` (larger), `same` when the change of the distance
/// is within the cell's
/// tolerance or within the 95 % half-width of the difference of the two means (the two cells'
/// intervals added in quadrature), the bounds the verdict code judges a cell by; `n/a` where a
/// run has no value. A cell that repeats an earlier cell's numbers in both runs is counted once.

#include <map>
#include <string>
#include <vector>

#include "reproduce/thesis_campaign.h"

namespace nimble::reproduce {

/// How a cell moved from `without` to `with` against its reference (see above).
std::string moved(const Cell& without, const Cell& with);

/// One cell in both runs.
struct BesideCell {
  Cell without, with;
  std::string moved;
};

struct BesideTable {
  std::string id, title, category, why;
  std::vector<BesideCell> cells;
};

struct BesideResult {
  CampaignResult without, with;
  std::vector<BesideTable> tables;
  /// Category -> moved (toward, away, same, n/a) -> cells.
  std::map<std::string, std::map<std::string, int>> moved_counts() const;
  /// Category -> "verdict without -> verdict with" -> cells whose verdict changed.
  std::map<std::string, std::map<std::string, int>> verdict_changes() const;
};

/// The two runs' tables side by side. @throws std::runtime_error if their tables or cells differ
/// in number or name (the same campaign file gives the same ones).
BesideResult merge_beside(CampaignResult without, CampaignResult with);

/// Flies the campaign without `options.overrides` and with them (each run's logs, figures and
/// campaign directory in a subdirectory `without` and `with` of the ones given) and merges them.
/// @throws std::invalid_argument without overrides; std::runtime_error for a campaign directory
/// that holds one campaign; as run_campaign().
BesideResult run_beside(const CampaignOptions& options);

/// The tables side by side as text, the counts of each run by category and verdict, and the
/// moved and verdict-change counts.
std::string beside_text(const BesideResult& result);

/// `{"beside": true, "overrides", "tables": [{"id", "title", "category", "why", "cells": [{"row",
/// "column", "published", "tolerance", "category", "rig_without", "rig_with", "interval_without",
/// "interval_with", "verdict_without", "verdict_with", "moved", "without": cell, "with": cell}]}],
/// "moved": {category: {moved: n}}, "verdict_changes": {category: {"a -> b": n}}, "without":
/// campaign_json(), "with": campaign_json()}`.
std::string beside_json(const BesideResult& result);

}  // namespace nimble::reproduce
