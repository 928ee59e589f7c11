#pragma once
/// The campaign report of `rig sweep ... --report DIR`: per parameter set, the envelopes of p, v
/// and phi across seeds against time (median and the 5 % and 95 % percentiles at each grid
/// time) and the controlled rate with its 95 % Wilson interval, written as `envelopes.csv`,
/// `report.json`, one SVG figure per set (`set-K.svg`, K from 1) and `index.html`.
/// The same SweepResult gives byte-identical files: nothing of the machine, the wall clock or the
/// number of jobs goes into them.

#include <string>
#include <vector>

#include "core/proportion.h"
#include "campaign/sweep.h"

namespace nimble::campaign {

/// One quantity across the runs of a set, on the set's time grid t_k = k dt_s.
struct Envelope {
  std::vector<double> t_s;           ///< grid times [s]
  std::vector<int> n;                ///< runs with a (finite) sample at that time
  std::vector<double> p5, p50, p95;  ///< percentiles over those runs (NaN where n is 0), in the quantity's unit
};

/// What the report says of one parameter set.
struct SetReport {
  std::string label;
  int runs = 0;        ///< runs of the set
  int controlled = 0;  ///< of which controlled
  int traces = 0;      ///< of which have a trace
  double dt_s = 0.0;   ///< the traces' grid step [s]; 0: no trace
  Proportion rate;     ///< controlled / runs with its 95 % Wilson interval
  Envelope p;          ///< roll rate [rad/s]
  Envelope v;          ///< lateral velocity [m/s]
  Envelope phi_deg;    ///< roll [deg]
};

/// The report's figures, one entry per parameter set in order. A run's trace counts up to the
/// shortest of its p, v and phi; non-finite samples are left out of n and the percentiles.
/// @throws std::invalid_argument if the traces of a set have different dt_s (naming the set), a
///   trace with samples has no positive dt_s, or a run names a set that does not exist.
std::vector<SetReport> sweep_report_sets(const SweepResult& result);

/// Writes `envelopes.csv`, `report.json`, `set-K.svg` for every set and `index.html` into `dir`
/// (made if missing). Everything is computed before the first file is written.
/// @throws std::invalid_argument as sweep_report_sets.
/// @throws std::runtime_error naming the directory or the file that could not be written.
void write_sweep_report(const SweepResult& result, const std::string& dir);

}  // namespace nimble::campaign
