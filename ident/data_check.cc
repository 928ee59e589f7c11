#include "ident/data_check.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <initializer_list>

namespace nimble::ident {
namespace {

std::string number(double x, const char* format) {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

/// Checks one channel; updates `best` when its first bad sample is earlier.
void check_channel(const std::string& name, const Channel& c, const DataBounds& bounds,
                   std::optional<BadSample>& best) {
  const std::optional<ChannelBound> bound = channel_bound(name, bounds);
  const std::size_t n = std::min(c.t_s.size(), c.values.size());
  for (std::size_t k = 0; k < n; ++k) {
    const double t = c.t_s[k], x = c.values[k];
    const bool finite = std::isfinite(t) && std::isfinite(x);
    if (finite && (!bound || std::fabs(x) <= bound->value)) continue;
    // A sample with a bad time sorts first: its place in time is unknown.
    const double when = std::isfinite(t) ? t : -INFINITY;
    if (!best || when < best->t_s) {
      BadSample b;
      b.channel = name;
      b.index = k;
      b.t_s = when;
      b.value = x;
      b.finite = finite;
      if (finite) b.bound = *bound;
      best = b;
    }
    return;  // later samples of this channel are later in time
  }
}

}  // namespace

std::optional<ChannelBound> channel_bound(const std::string& channel, const DataBounds& b) {
  const auto is = [&](std::initializer_list<const char*> names) {
    for (const char* n : names) {
      if (channel == n) return true;
    }
    return false;
  };
  if (is({"p", "q", "r"})) return ChannelBound{b.rate_max_radps, "data_bounds.rate_max_radps"};
  if (is({"u", "v", "w"})) return ChannelBound{b.speed_max_mps, "data_bounds.speed_max_mps"};
  if (is({"phi", "theta", "phi_sp"})) return ChannelBound{b.angle_max_rad, "data_bounds.angle_max_rad"};
  if (is({"delta_f", "delta_f_cmd"})) return ChannelBound{b.delta_f_max_radps, "data_bounds.delta_f_max_radps"};
  if (is({"delta_t"})) return ChannelBound{b.throttle_max_pct, "data_bounds.throttle_max_pct"};
  if (is({"delta_d", "delta_w"})) return ChannelBound{b.servo_max_rad, "data_bounds.servo_max_rad"};
  if (is({"ax", "ay", "az"})) return ChannelBound{b.specific_force_max_mps2, "data_bounds.specific_force_max_mps2"};
  return std::nullopt;  // t, psi (a heading may be unwrapped; the toolkit does not use it)
}

std::optional<BadSample> first_bad_sample(const FlightData& data, const DataBounds& bounds) {
  std::optional<BadSample> best;
  // Canonical order first, so that a tie in time names the channel the CSV header lists first.
  for (const ChannelSpec& spec : channel_specs()) {
    const auto it = data.channels.find(spec.name);
    if (it != data.channels.end()) check_channel(it->first, it->second, bounds, best);
  }
  for (const auto& [name, c] : data.channels) {
    if (!is_known_channel(name)) check_channel(name, c, bounds, best);
  }
  return best;
}

RefusedData::RefusedData(const std::string& source, const BadSample& bad, const std::string& message)
    : DataError(source, -1, static_cast<int>(bad.index + 1), bad.channel, message),
      message_("refused: " + source + ": " + message),
      time_s_(bad.t_s) {}

void check_flight_data(const FlightData& data, const Vehicle& vehicle) {
  const std::optional<BadSample> bad = first_bad_sample(data, vehicle.data_bounds);
  if (!bad) return;
  std::string unit;
  if (is_known_channel(bad->channel)) unit = " " + channel_spec(bad->channel).unit;
  const std::string at = std::isfinite(bad->t_s) ? "at t = " + number(bad->t_s, "%.4f") + " s"
                                                 : "at sample " + std::to_string(bad->index + 1) + " (its time is not finite)";
  std::string message;
  if (!bad->finite) {
    message = bad->channel + " = " + number(bad->value, "%g") + " " + at + " is not a finite number";
  } else {
    const std::string where = vehicle.file.empty() ? "vehicle " + vehicle.name : "vehicle file " + vehicle.file;
    message = bad->channel + " = " + number(bad->value, "%.4g") + unit + " " + at + " exceeds the physical bound " +
              number(bad->bound.value, "%g") + unit + " (" + where + ", bound " + bad->bound.key + ")";
  }
  throw RefusedData(data.source, *bad, message);
}

}  // namespace nimble::ident
