#pragma once
/// The power analysis's report: terminal text, JSON (keys in power_json()) and the power curves
/// as PNG plots drawn by gnuplot.

#include <string>
#include <vector>

#include "detection_power/power_campaign.h"

namespace nimble::detection_power {

/// The tables (naming probability with its interval, other names, alarms per cell), the
/// recommended length per size, the smallest size per length, the verification and the time.
std::string power_text(const PowerResult& result);

/// JSON: scenario, model, effect, parameter, unit, named_as, block_s, target, flights_per_cell,
/// seed, jobs, sizes, lengths_s, cells (size, length_s, repetitions, flights, named, other, alarm
/// as {count, n, p, lo, hi}, other_names, verdicts, not_ok, failed, kind, flight_s_mean,
/// workflow_s_mean, flight_cpu_s_mean, workflow_cpu_s_mean),
/// recommended_length (per size: size, reached, length_s, note), smallest_size (per length),
/// verification (cells), timing (wall_s, setup_s, flights, flight_s_mean, workflow_s_mean), plots.
std::string power_json(const PowerResult& result, const std::vector<std::string>& plots = {});

/// Writes into `dir` (created if needed) power_length.png (the naming probability against the
/// record length, one curve per size, 95 % intervals as error bars, the target as a line, the
/// recommended lengths marked) and power_size.png (against |size|, one curve per length), with
/// their .dat and .gp files. Returns the PNG paths.
/// @throws std::runtime_error if gnuplot is missing or fails.
std::vector<std::string> write_power_plots(const PowerResult& result, const std::string& dir);

}  // namespace nimble::detection_power
