#pragma once
/// Recorded flight data for identification: named channels with their own time
/// stamps, read from and written to CSV.
///
/// CSV format (one file per flight):
///  - optional `#` comment lines at the top of the file, before the header;
///  - a header row naming the columns, comma separated, in any order;
///  - one data row per sample, every cell a finite decimal number;
///  - column `t` [s] strictly increasing; the other columns share it.
/// Required columns: t, p, v, phi, delta_f, delta_t. Optional: r, q, u, w,
/// theta, psi, delta_d, delta_w, ax, ay, az, phi_sp, delta_f_cmd (see channel_specs()).
/// A column outside these is an error. Blank lines are skipped.
///
/// A flight-log reader fills FlightData directly, each channel at its own
/// rate (IMU 512 Hz, motion capture 200 Hz, throttle 5 Hz); resample_uniform()
/// (ident/signal.h) puts every channel on one uniform grid.

#include <cstddef>
#include <map>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/data_error.h"

namespace nimble::ident {

/// Name, unit and role of one flight-data channel.
struct ChannelSpec {
  std::string name;  ///< CSV column name, e.g. "delta_f"
  std::string unit;  ///< SI unit, e.g. "rad/s"; "%" for delta_t
  bool required;     ///< must be present in every CSV file
  std::string what;  ///< one-line description
};

/// Every channel the rig knows, in the canonical column order (time first).
const std::vector<ChannelSpec>& channel_specs();

/// Spec of `name`; @throws std::out_of_range for an unknown channel.
const ChannelSpec& channel_spec(const std::string& name);

/// True if `name` is a known channel (other than the time column "t").
bool is_known_channel(const std::string& name);

/// One recorded signal: strictly increasing time stamps [s] and its values
/// (in the unit of its ChannelSpec).
struct Channel {
  std::vector<double> t_s;
  std::vector<double> values;
};

/// A flight record: channels by name. For CSV data every channel holds the
/// same time stamps; a log reader may give each channel its own.
struct FlightData {
  std::string source;  ///< file or log it came from, used in messages
  std::map<std::string, Channel> channels;
  /// Where a channel read from a log came from: its LCM channel and message field
  /// (TRUTH, omega_body_radps[0]), for naming its samples (ident/data_check.h); none for a CSV file.
  std::map<std::string, std::pair<std::string, std::string>> origin;

  /// True if the record has channel `name`.
  bool has(const std::string& name) const { return channels.count(name) != 0; }
  /// Channel `name`; @throws std::out_of_range naming the channel and the source if absent.
  const Channel& at(const std::string& name) const;
  /// Smallest number of samples over all channels (0 if there are none).
  std::size_t min_samples() const;
};

/// Error in flight data (core/data_error.h).
using DataError = ::nimble::DataError;

/// Parses CSV text (format above); `source` names it in errors.
/// @throws DataError on a missing required column, an unknown or duplicate
///         column, a row with the wrong number of cells, an empty,
///         non-numeric or non-finite cell, a time that does not increase, or
///         fewer than two data rows.
FlightData parse_flight_csv(const std::string& text, const std::string& source);

/// Reads a CSV file, refused before it is read if it is no regular file or is above the bound of
/// a flight record (kMaxRecordSamples rows of kMaxRecordLineBytes, core/input_file.h).
/// @throws DataError as parse_flight_csv, or naming the file if it cannot be read or is refused.
FlightData read_flight_csv(const std::string& file);

/// CSV text of `data`: a units comment line, the header (canonical order) and
/// one row per sample, numbers with 17 significant digits (round-trip exact).
/// @throws std::invalid_argument if a channel is unknown, required channels
///         are missing, or the channels do not share one time vector.
std::string format_flight_csv(const FlightData& data);

/// Writes format_flight_csv(data) to `file`.
/// @throws std::runtime_error if the file cannot be written; as format_flight_csv.
void write_flight_csv(const FlightData& data, const std::string& file);

/// Flight data from columns on one time base (a user's own arrays, no file): `t_s` [s] finite and
/// strictly increasing; every column a known channel (not "t") with one value per time stamp;
/// the required channels present; every value finite. `source` names it in errors.
/// @throws DataError naming the column ("t" for the time base) and the 1-based sample, or the
///         missing required channel; std::invalid_argument for an unknown channel (listing the
///         known ones) or a column whose length is not that of `t_s`.
FlightData flight_data_from_columns(const std::string& source, const std::vector<double>& t_s,
                                    std::map<std::string, std::vector<double>> columns);

/// Checks that every channel has as many values as time stamps, finite values
/// and strictly increasing time.
/// @throws DataError naming the channel and the 1-based sample index.
void validate_flight_data(const FlightData& data);

}  // namespace nimble::ident
