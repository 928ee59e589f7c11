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
/// Verdicts: `match` within the table's tolerance, `explained` outside it with a reason written
/// in the campaign file, `differs` otherwise.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace nimble::reproduce {

/// One cell of a reproduced table.
struct Cell {
  std::string row, column;
  double published = 0.0;
  double rig = 0.0;
  std::string verdict;  ///< "match", "explained" or "differs"
  std::string reason;   ///< the campaign file's reason (explained), or why it differs
};

struct Table {
  std::string id;     ///< thesis table number, e.g. "9.4"
  std::string title;
  std::string tolerance;  ///< what `match` means, in words
  std::vector<Cell> cells;
};

struct FlightRecord {
  std::string name;      ///< the campaign file's flight name
  std::string scenario;  ///< scenario file
  std::string log;       ///< its log
  std::string result;    ///< the run's verdict text
  bool controlled = false;
  double sim_s = 0.0;    ///< simulated time flown
  double wall_s = 0.0;
};

struct CampaignResult {
  std::string campaign;  ///< campaign file
  std::string clock;
  std::uint64_t seed = 1;
  std::string states;  ///< where the measured states come from
  std::vector<FlightRecord> flights;
  std::vector<Table> tables;
  double wall_s = 0.0;
  /// Cells by verdict.
  std::map<std::string, int> counts() const;
};

struct CampaignOptions {
  std::string campaign_file;
  std::string clock = "inprocess";  ///< inprocess, lockstep or realtime (the last two through `rig run`)
  std::uint64_t seed = 1;
  std::string work_dir;             ///< logs land here
  std::string rig_exe;              ///< `rig` itself, for the lockstep and real-time clocks
  std::string report_dir;           ///< figures (empty: none)
  std::string controller_file;      ///< the controller copy of the closed-loop validation
  /// Where the identification and validation take the states: "estimate" (the EKF's, as the
  /// thesis's data came through its EKF; the default) or "truth" (the plant's).
  std::string states = "estimate";
  bool progress = false;            ///< a line per flight on stderr
};

/// Flies the campaign and builds the tables.
/// @throws ConfigError for a bad campaign file; std::runtime_error if a flight cannot be flown.
CampaignResult run_campaign(const CampaignOptions& options);

/// The tables side by side as text.
std::string campaign_text(const CampaignResult& result);

/// `{"tables": [{"id", "title", "tolerance", "cells": [{"row", "column", "published", "rig", "verdict",
/// "reason"}]}], "counts": {...}, "flights": [...]}`.
std::string campaign_json(const CampaignResult& result);

}  // namespace nimble::reproduce
