#pragma once
/// `rig reproduce thesis`: the thesis's flight campaign flown by the rig, identified and validated
/// as the thesis did, and every table it can reproduce set beside the published one.
///
/// The campaign file (rig_configs/reproduce/thesis.yaml) names the flights (scenario files), the
/// model sets whose identification flights Table 9.4 and 9.5 need, and per table the published
/// values, the tolerance of a `match` and the reasons of cells that are `explained`. This module
/// flies, identifies, validates and judges:
///  - 9.4  state ranges of each set's identification flight (the train flown on that set's model,
///         with that set's excitation: the campaign file may name a manoeuvre per set);
///  - 9.5  eigenvalues of the model identified from each of those flights;
///  - 9.6  non-dimensional derivatives (thesis Eq 9.2) of the model identified from set 1's flight;
///  - 4    the identification's equation-error fit (set 1);
///  - 7, 8, 15, 16  open-loop validation of set 1's identified model on the 6 Hz doublet, the
///         1-1-2 and the 30 deg and 20 deg nonlinear doublets (state-derivative fits);
///  - 9, 10, 11  closed-loop validation (the model flown by a controller copy) on the
///         identification train (fast gains), the slow-gain doublet train and 1-1-2s;
///  - 8.8  eigenvalues of the four-state model file (Table 8.3, trim of Eq D.1).
/// The identification is the thesis's (WLS on Eq 21's equation error, trim w0 the flight's
/// initial w, Table 9.3) with one regressor added to the side-force equation: p (w - w0), the
/// part of the exact kinematic term m p w that Eq 21 fixes at w0. The pilot moves w away from
/// w0 during the flight; the coefficient found is reported (it is the mass when the plant is
/// the rig's).
///
/// Verdicts and categories: reproduce/cell_verdict.h. Every cell is judged on the mean over the
/// seeds flown (--seeds); a reason's check that names a cause flies the table's flight again
/// with that cause added, with the same seeds.
///
/// The closed-loop causes (campaign file `closed_loop_causes`): the closed-loop tables 9-11 flown
/// again with each cause the thesis gives for its closed-loop misfit, sized from elsewhere (the
/// practical's turbulence, the plant's flapping forcing), and where their cells move reported
/// beside the published values, whichever way.

#include <cstdint>
#include <complex>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "reproduce/cell_verdict.h"
#include "scenario/scenario.h"

namespace nimble::reproduce {

struct Table {
  std::string id;  ///< thesis table number, e.g. "9.4"
  std::string title;
  std::string category;        ///< reproduce/cell_verdict.h
  std::string why;             ///< what the cells are computed from (the category's ground)
  bool against_plant = false;  ///< a pipeline check: cells judged against the plant file's values
  std::vector<Cell> cells;
};

/// One closed-loop cell flown with and without one cause of the thesis's misfit.
struct CauseCell {
  std::string table, row, column;
  double published = 0.0;
  double rig = 0.0;         ///< mean over the seeds, without the cause
  double with_cause = 0.0;  ///< mean over the seeds, with it
  double interval = 0.0;    ///< 95 % half-width of with_cause's mean
};

/// A derivative identified from the identification flights against the plant's own (the model the
/// flight flew): the rig's check of its states and pipeline, not a thesis cell.
struct PlantCheck {
  std::string row;         ///< "set N"
  std::string derivative;  ///< e.g. "Yv"
  std::string method;      ///< "equation error" (the thesis's WLS) or "output error"
  double plant = 0.0;
  double mean = 0.0;      ///< over the seeds
  double sd = 0.0;        ///< seed-to-seed
  double interval = 0.0;  ///< 95 % half-width of the mean
  /// The method's own standard deviation of one flight's estimate (Cramer-Rao or regression,
  /// allowing coloured residuals), mean over the seeds: beside `sd`, whether the method knows
  /// how well one flight determines the derivative.
  double own_sd = 0.0;
};

struct CauseStudy {
  std::string name;                    ///< e.g. "flapping forcing"
  std::string source;                  ///< where its size comes from
  std::vector<std::string> overrides;  ///< key=value
  std::vector<CauseCell> cells;
  std::vector<std::string> failures;  ///< flights with the cause that did not fly as their scenario asks
};

struct FlightRecord {
  std::string name;  ///< the campaign file's flight name
  std::uint64_t seed = 1;
  std::string scenario;  ///< scenario file
  std::string log;       ///< its log
  std::string result;    ///< the run's verdict text
  bool controlled = false;
  double sim_s = 0.0;  ///< simulated time flown
  double wall_s = 0.0;
};

struct CampaignResult {
  std::string campaign;  ///< campaign file
  std::string clock;
  std::vector<std::string> overrides;  ///< key=value, on every flight (CampaignOptions::overrides)
  std::vector<std::uint64_t> seeds;
  std::string states;  ///< where the measured states come from
  std::vector<FlightRecord> flights;
  std::vector<Table> tables;
  std::vector<CauseStudy> causes;
  std::vector<PlantCheck> plant_check;
  double wall_s = 0.0;
  /// Cells by category and verdict; a cell that repeats an earlier one's numbers counts once.
  std::map<std::string, std::map<std::string, int>> counts() const;
  /// Cells with verdict `differs`, a repeat of an earlier cell's numbers included (the exit code:
  /// a repeat is counted once in counts(), but a difference is never dropped).
  int differing() const;
};

struct CampaignOptions {
  std::string campaign_file;
  std::string clock = "inprocess";  ///< inprocess, lockstep or realtime (the last two through `rig run`)
  std::vector<std::uint64_t> seeds{1, 2, 3, 4, 5};  ///< every flight is flown with each
  std::string work_dir;                             ///< logs land here
  std::string rig_exe;                              ///< `rig` itself, for the lockstep and real-time clocks
  std::string report_dir;                           ///< figures (empty: none)
  std::string controller_file;                      ///< the controller copy of the closed-loop validation
  /// Where the identification and validation take the states: "smoothed" (made offline from the
  /// log's IMU and motion capture, as the thesis's were; the default), "estimate" (the on-board
  /// EKF's) or "truth" (the plant's).
  std::string states = "smoothed";
  bool progress = false;  ///< a line per flight on stderr
  /// Seeds flown at a time, each in a worker of the campaigns' pool (campaign/worker_pool.h); the
  /// tables are the same for any number.
  int jobs = 1;
  /// A campaign directory (campaign/result_files.h) keeping each seed's values as it finishes
  /// (empty: none): the same campaign started again there flies only the seeds it lacks.
  std::string result_dir;
  /// Scenario overrides on every flight of the campaign (`--set`, e.g. sensing.base=FILE), under
  /// each flight's own (a set's model, a cause's `with`); they are part of what identifies a
  /// campaign directory.
  std::vector<Override> overrides;
};

/// `options.overrides` followed by a flight's own: what the flight is flown with.
std::vector<Override> flight_overrides(const CampaignOptions& options, const std::vector<Override>& own);

/// `key=value` of each override, in order.
std::vector<std::string> override_texts(const std::vector<Override>& overrides);

/// Flies the campaign and builds the tables.
/// @throws ConfigError for a bad campaign file; std::runtime_error if a flight cannot be flown.
CampaignResult run_campaign(const CampaignOptions& options);

/// The tables side by side as text.
std::string campaign_text(const CampaignResult& result);

/// `{"campaign", "clock", "seeds", "states", "overrides": ["key=value"], ..., "tables": [{"id", "title",
/// "category", "why", "against" ("published" or "plant file"), "cells": [{"row", "column", "published",
/// "reference" (what the cell is judged against), "rig", "values" (per seed), "rig_sd", "interval",
/// "seeds", "tolerance", "tolerance_basis", "category", "verdict", "reason", "check": {"predicate", "holds", "value"}, "repeats"}]}],
/// "counts": {category: {verdict: n}}, "match_share", "causes": [...], "flights": [...]}`.
std::string campaign_json(const CampaignResult& result);

/// Fig 9.1: every set's identified eigenvalues (`rig`: set row, eigenvalues) with the published
/// ones of Table 9.5, on one map (eigenvalues_9_1.png in `dir`).
void plot_eigenvalue_map(const std::string& dir,
                         const std::vector<std::pair<std::string, std::vector<std::complex<double>>>>& rig,
                         const TableSpec& published);

}  // namespace nimble::reproduce
