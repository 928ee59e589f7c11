#include "ident/data_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace nimble::ident {
namespace {

void tally_channel(const FlightData& data, const std::string& name, const Channel& c, BoundsTally& tally) {
  const auto origin = data.origin.find(name);
  const std::string channel = origin == data.origin.end() ? "" : origin->second.first;
  const std::string field = origin == data.origin.end() ? name : origin->second.second;
  const std::size_t n = std::min(c.t_s.size(), c.values.size());
  for (std::size_t k = 0; k < n; ++k) {
    if (!tally.fits(name.c_str(), c.t_s[k], c.values[k])) tally.count(channel, field, name, c.t_s[k], c.values[k]);
  }
}

/// The 0-based index of the first sample of `c` that does not fit `quantity`'s bound.
std::size_t first_unfit(const Channel& c, const std::string& quantity, const BoundsTally& tally) {
  const std::size_t n = std::min(c.t_s.size(), c.values.size());
  for (std::size_t k = 0; k < n; ++k) {
    if (!tally.fits(quantity.c_str(), c.t_s[k], c.values[k])) return k;
  }
  return 0;
}

std::string number(double x) {
  char buf[48];
  std::snprintf(buf, sizeof buf, "%.4g", x);
  return buf;
}

/// "zero throughout (N samples)" or "constant throughout (= X, N samples)"; "" if `c` moves.
std::string stands_still(const Channel& c) {
  if (c.values.empty()) return "";
  const double first = c.values.front();
  for (const double x : c.values) {
    if (x != first) return "";
  }
  const std::string n = std::to_string(c.values.size()) + (c.values.size() == 1 ? " sample" : " samples");
  return first == 0.0 ? "zero throughout (" + n + ")" : "constant throughout (= " + number(first) + ", " + n + ")";
}

}  // namespace

void tally_flight_data(const FlightData& data, BoundsTally& tally) {
  // Canonical order first, so that a tie in time names the channel the CSV header lists first.
  for (const ChannelSpec& spec : channel_specs()) {
    const auto it = data.channels.find(spec.name);
    if (it != data.channels.end()) tally_channel(data, it->first, it->second, tally);
  }
  for (const auto& [name, c] : data.channels) {
    if (!is_known_channel(name)) tally_channel(data, name, c, tally);
  }
}

RefusedData::RefusedData(const std::string& source, const std::string& channel, std::size_t index, double time_s,
                         const std::string& message)
    : DataError(source, -1, static_cast<int>(index + 1), channel, message),
      message_("refused: " + source + ": " + message),
      time_s_(time_s) {}

RefusedData::RefusedData(const std::string& source, const BoundsTally& tally)
    : DataError(source, -1, static_cast<int>(tally.earliest().first_event), BoundsTally::name(tally.earliest()),
                tally.refusal()),
      message_("refused: " + source + ": " + tally.refusal()),
      time_s_(tally.earliest().first_t_s) {}

void check_flight_data(const FlightData& data, const Vehicle& vehicle) {
  BoundsTally tally(vehicle);
  tally_flight_data(data, tally);
  if (tally.empty()) return;
  const BoundsTally::Entry& first = tally.earliest();
  const std::size_t index = first_unfit(data.at(first.quantity), first.quantity, tally);
  throw RefusedData(data.source, first.quantity, index, first.first_t_s, tally.refusal());
}

UnexcitedData::UnexcitedData(const std::string& source, const std::string& column, const std::string& problem)
    : DataError(source, -1, -1, column, problem), message_("refused: " + source + ": " + problem) {}

void check_excitation(const FlightData& data, const std::vector<std::string>& states,
                      const std::vector<std::string>& inputs) {
  const std::string why = "; nothing can be identified, validated or found in a record that does not move";
  for (const std::string& s : states) {
    if (!data.has(s)) continue;
    const std::string still = stands_still(data.at(s));
    if (!still.empty()) throw UnexcitedData(data.source, s, "no excitation: " + s + " is " + still + why);
  }
  std::string names, first;
  for (const std::string& u : inputs) {
    if (!data.has(u)) continue;
    if (stands_still(data.at(u)).empty()) return;  // one input moves
    if (first.empty()) first = u;
    names += (names.empty() ? "" : ", ") + u;
  }
  if (names.empty()) return;  // no input in the data: the analysis names what it misses
  throw UnexcitedData(data.source, first,
                      "no excitation: no input moves (" + names + " constant throughout, " +
                          std::to_string(data.at(first).values.size()) + " samples)" + why);
}

}  // namespace nimble::ident
