// Fuzz target: the flight-data CSV reader (ident/flight_data.h, parse_flight_csv). Bad text is a
// DataError; text it takes must survive writing (format_flight_csv) and reading again with the
// same channels and samples.

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_support.h"
#include "ident/flight_data.h"

using nimble::fuzz::require;

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  const std::string text(reinterpret_cast<const char*>(data), size);
  nimble::ident::FlightData flight;
  try {
    flight = nimble::ident::parse_flight_csv(text, "fuzz.csv");
  } catch (const nimble::ident::DataError&) {
    return 0;  // the documented outcome of bad CSV
  }
  const std::string written = nimble::ident::format_flight_csv(flight);
  nimble::ident::FlightData again;
  try {
    again = nimble::ident::parse_flight_csv(written, "written.csv");
  } catch (const nimble::ident::DataError& e) {
    nimble::fuzz::finding(std::string("CSV written for data that was read does not read back: ") + e.what());
  }
  require(again.channels.size() == flight.channels.size(), "CSV round trip changed the number of channels");
  for (const auto& [name, channel] : flight.channels) {
    const auto it = again.channels.find(name);
    require(it != again.channels.end(), "CSV round trip lost channel " + name);
    require(it->second.values == channel.values && it->second.t_s == channel.t_s,
            "CSV round trip changed the samples of channel " + name);
    for (double v : channel.values) require(std::isfinite(v), "CSV reader took a non-finite value in " + name);
  }
  return 0;
}
