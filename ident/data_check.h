#pragma once
/// Refusing flight data that cannot be a measurement of the vehicle: a sample that is not a
/// finite number, or whose magnitude exceeds the vehicle's physical bound for its channel
/// (Vehicle::data_bounds, the vehicle file's `data_bounds` section with their sources). A
/// diverged simulation or a corrupted record would otherwise be identified, validated or have
/// effects named as if it had flown. identify(), validate_open_loop(), validate_closed_loop()
/// and find_discrepancy() (every flight of a pool) call check_flight_data() before anything else.

#include <cstddef>
#include <optional>
#include <string>

#include "core/vehicle.h"
#include "ident/flight_data.h"

namespace nimble::ident {

/// The bound of `channel`: its value in `bounds` and its key in the vehicle file
/// ("data_bounds.rate_max_radps"); nullopt for a channel without one (t, psi: finiteness only).
struct ChannelBound {
  double value = DataBounds::kNone;
  std::string key;
};
std::optional<ChannelBound> channel_bound(const std::string& channel, const DataBounds& bounds);

/// The first bad sample of a record: the earliest in time over every channel (ties in the
/// canonical channel order).
struct BadSample {
  std::string channel;
  std::size_t index = 0;  ///< 0-based sample of the channel
  double t_s = 0.0;
  double value = 0.0;
  bool finite = true;     ///< false: the value (or its time) is NaN or infinite
  ChannelBound bound;     ///< the bound it exceeds (finite samples)
};

/// The first sample of `data` that is not finite or exceeds its channel's bound, if any.
std::optional<BadSample> first_bad_sample(const FlightData& data, const DataBounds& bounds);

/// A record refused as not finite or not physical. what():
/// "refused: flight.csv: p = 2.1e+06 rad/s at t = 3.4121 s exceeds the physical bound 50 rad/s
/// (vehicle file rig_configs/vehicles/nimble_no_wifi.yaml, bound data_bounds.rate_max_radps)".
/// row() is the 1-based sample of the channel, column() the channel.
class RefusedData : public DataError {
 public:
  RefusedData(const std::string& source, const BadSample& bad, const std::string& message);
  const char* what() const noexcept override { return message_.c_str(); }
  /// Time of the first bad sample [s].
  double time_s() const { return time_s_; }

 private:
  std::string message_;
  double time_s_;
};

/// Refuses `data` if any sample is not finite or exceeds `vehicle`'s data bound for its channel.
/// @throws RefusedData naming the source, the first bad sample's channel, value and time, and the
///         bound with the vehicle file it comes from.
void check_flight_data(const FlightData& data, const Vehicle& vehicle);

}  // namespace nimble::ident
