#pragma once
/// Refusing flight data that cannot be a measurement of the vehicle: a sample that is not a
/// finite number, or whose magnitude exceeds the vehicle's physical bound for its channel
/// (Vehicle::data_bounds, the vehicle file's `data_bounds` section with their sources, checked by
/// core/data_bounds.h's BoundsTally, the one check every reader applies), and a record without
/// excitation (a state constant throughout, or no input that moves). A diverged simulation, a
/// corrupted record or a record of nothing would otherwise be identified, validated or have
/// effects named as if it had flown. identify(), validate_open_loop(), validate_closed_loop()
/// and find_discrepancy() (every flight of a pool) call check_flight_data() and
/// check_excitation() before anything else.

#include <cstddef>
#include <string>
#include <vector>

#include "core/data_bounds.h"
#include "core/vehicle.h"
#include "ident/flight_data.h"

namespace nimble::ident {

/// Counts every sample of `data` that is not finite or beyond its channel's bound into `tally`,
/// channels in the canonical order; a channel read from a log (FlightData::origin) is named by
/// its LCM channel and field, any other by its column.
void tally_flight_data(const FlightData& data, BoundsTally& tally);

/// A record refused as not finite or not physical. what(), BoundsTally::refusal():
/// "refused: flight.csv: p = 2.1e+06 rad/s at t = 3.4121 s exceeds the physical bound 50 rad/s
/// (vehicle file rig_configs/vehicles/nimble_no_wifi.yaml, bound data_bounds.rate_max_radps); 12
/// samples beyond the physical bounds of vehicle file ...: p: 12 samples beyond ...".
/// row() is the 1-based sample of the channel, column() the channel.
class RefusedData : public DataError {
 public:
  RefusedData(const std::string& source, const std::string& channel, std::size_t index, double time_s,
              const std::string& message);
  /// A log refused by what a reader counted (an export's --strict): column() the earliest
  /// entry's channel and field, row() its event number (-1 if none), the message
  /// BoundsTally::refusal(). Not on an empty tally.
  RefusedData(const std::string& source, const BoundsTally& tally);
  const char* what() const noexcept override { return message_.c_str(); }
  /// Time of the first bad sample [s].
  double time_s() const { return time_s_; }

 private:
  std::string message_;
  double time_s_;
};

/// Refuses `data` if any sample is not finite or exceeds `vehicle`'s data bound for its channel.
/// @throws RefusedData naming the source, the first bad sample's channel, value and time, the
///         bound with the vehicle file it comes from, and the count of bad samples by channel.
void check_flight_data(const FlightData& data, const Vehicle& vehicle);

/// A record refused as without excitation. what():
/// "refused: flight.csv: no excitation: p is zero throughout (3071 samples); nothing can be
/// identified, validated or found in a record that does not move".
class UnexcitedData : public DataError {
 public:
  UnexcitedData(const std::string& source, const std::string& column, const std::string& problem);
  const char* what() const noexcept override { return message_.c_str(); }

 private:
  std::string message_;
};

/// Refuses `data` if one of `states` it holds is constant throughout (zero or not), or if none of
/// `inputs` it holds moves (every one constant throughout): the one test of excitation of every
/// analysis. An input of its own may stand still (a throttle held at trim); a state may not.
/// @throws UnexcitedData naming the source and the channel (the first state, or every input).
void check_excitation(const FlightData& data, const std::vector<std::string>& states,
                      const std::vector<std::string>& inputs);

}  // namespace nimble::ident
