#pragma once
/// What the commands that read flight data share (identify, validate, discrepancy, export): the
/// options that say how a rig log is read, the processing options, and how a damaged or
/// partly undecodable log is reported.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "core/data_bounds.h"
#include "ident/identify.h"
#include "ident/rig_log.h"
#include "ident/signal.h"
#include "mcap/log_export.h"

namespace nimble::cli {

/// "A:B" [s] as a time range. @throws std::invalid_argument naming the text.
ident::TimeRange time_range(const std::string& text);

/// "a,b,c" as a list (empty items left out).
std::vector<std::string> split_list(const std::string& text);

/// --rate, --cutoff, --order, --interpolation: the processing every analysis command shares.
void add_processing(cmdline::CommandLine& cl, ident::ProcessingOptions& p);

/// --salvage: read a damaged log up to the damage.
void add_salvage(cmdline::CommandLine& cl, ident::LogReadOptions& o);

/// --states SOURCE and --sensing FILE: where a rig log's states come from, and the sensing the
/// smoother's filter is matched to. Returns the --states option.
CLI::Option* add_states(cmdline::CommandLine& cl, ident::LogReadOptions& o, std::string& sensing_file);

/// Checks --states against the data files (a CSV file carries its own states: --states is for rig
/// logs) and sets the smoother's model from --sensing (or the default sensing file) for --states
/// smoothed. Returns the exit code of a usage error naming the file (reported through `cl`).
std::optional<int> apply_states(const cmdline::CommandLine& cl, ident::LogReadOptions& o,
                                const std::string& sensing_file, const std::vector<std::string>& data_files);

/// --vehicle FILE.
void add_vehicle(cmdline::CommandLine& cl, std::string& file, const std::string& default_text);

/// Says on stderr what a salvaged read left out.
void warn_damage(const char* command, const std::string& file, const std::string& damage);

/// Counts the undecodable messages a log reader passes over (the channels it does not read), as
/// the MCAP export counts what it leaves out: `o.other_event` feeds `count`.
void count_undecodable(ident::LogReadOptions& o, mcap::UndecodableCount& count);

/// Says on stderr which messages beyond the vehicle's physical bounds a read left out, by channel,
/// field, time and count (nothing when there were none).
void warn_beyond_bounds(const char* command, const std::string& file, const BoundsTally& beyond);

/// Says on stderr which undecodable messages a read left out, by channel and count.
void warn_undecodable(const char* command, const std::string& file, const mcap::UndecodableCount& count);

}  // namespace nimble::cli
