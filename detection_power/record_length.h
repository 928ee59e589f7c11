#pragma once
/// The record length of a power flight. A scenario flies its manoeuvre once in duration_s; a
/// longer record flies the same manoeuvre again, as a pilot would repeat it in one flight:
///  - the block is the scenario as it is: its manoeuvre, then level hover to duration_s (the
///    block is the manoeuvre alone if the scenario is shorter than it);
///  - a record of L seconds flies ceil(L / block) blocks back to back (a manoeuvre file with the
///    segments repeated, a level hold between repetitions for the hover), and duration_s = L:
///    the last block is cut at L when L is not a whole number of blocks;
///  - L = duration_s is the scenario as it is (no override), L below it cuts the scenario short.
/// Every repetition is the same manoeuvre (names of repeated segments get _2, _3, ...); the
/// seed's noise, gusts and sensor errors go on through the whole record.

#include <string>
#include <vector>

#include "scenario/scenario.h"

namespace nimble::detection_power {

/// How a scenario is flown for `length_s`.
struct RecordLength {
  double length_s = 0.0;
  double block_s = 0.0;             ///< one block: max(duration_s, the manoeuvre's duration)
  int repetitions = 1;              ///< blocks flown (the last one possibly cut)
  std::string manoeuvre_file;       ///< the repeated manoeuvre written (empty: the scenario's own)
  std::vector<Override> overrides;  ///< duration_s and manoeuvre
};

/// The block of `scenario` [s]. @throws ConfigError if its manoeuvre cannot be loaded.
double block_length_s(const Scenario& scenario);

/// Writes (into `dir`, which must exist) the manoeuvre that flies `scenario` for `length_s`
/// and returns the overrides. @throws std::invalid_argument unless length_s > 0 and finite;
/// ConfigError if the manoeuvre cannot be loaded; std::runtime_error if it cannot be written.
RecordLength record_length(const Scenario& scenario, double length_s, const std::string& dir);

}  // namespace nimble::detection_power
