#include "core/data_bounds.h"

#include <cmath>
#include <cstdio>
#include <cstring>
#include <utility>

#include "core/json_line.h"

namespace nimble {
namespace {

std::string number(double x, const char* format) {
  char buf[48];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string with_unit(double x, const std::optional<QuantityBound>& b) {
  return number(x, "%.4g") + (b && !b->unit.empty() ? " " + b->unit : "");
}

std::string at_time(const BoundsTally::Entry& e) {
  std::string at =
      std::isfinite(e.first_t_s) ? "at t = " + number(e.first_t_s, "%.4f") + " s" : "at a time that is not finite";
  if (e.first_event >= 0) at += " (event " + std::to_string(e.first_event) + ")";
  return at;
}

/// Each bounded quantity with its DataBounds member, key and unit.
struct QuantitySpec {
  const char* quantity;
  double DataBounds::*member;
  const char* key;
  const char* unit;
};

constexpr QuantitySpec kQuantities[] = {
    {"p", &DataBounds::rate_max_radps, "data_bounds.rate_max_radps", "rad/s"},
    {"q", &DataBounds::rate_max_radps, "data_bounds.rate_max_radps", "rad/s"},
    {"r", &DataBounds::rate_max_radps, "data_bounds.rate_max_radps", "rad/s"},
    {"u", &DataBounds::speed_max_mps, "data_bounds.speed_max_mps", "m/s"},
    {"v", &DataBounds::speed_max_mps, "data_bounds.speed_max_mps", "m/s"},
    {"w", &DataBounds::speed_max_mps, "data_bounds.speed_max_mps", "m/s"},
    {"phi", &DataBounds::angle_max_rad, "data_bounds.angle_max_rad", "rad"},
    {"theta", &DataBounds::angle_max_rad, "data_bounds.angle_max_rad", "rad"},
    {"phi_sp", &DataBounds::angle_max_rad, "data_bounds.angle_max_rad", "rad"},
    {"delta_f", &DataBounds::delta_f_max_radps, "data_bounds.delta_f_max_radps", "rad/s"},
    {"delta_f_cmd", &DataBounds::delta_f_max_radps, "data_bounds.delta_f_max_radps", "rad/s"},
    {"delta_t", &DataBounds::throttle_max_pct, "data_bounds.throttle_max_pct", "%"},
    {"delta_d", &DataBounds::servo_max_rad, "data_bounds.servo_max_rad", "rad"},
    {"delta_w", &DataBounds::servo_max_rad, "data_bounds.servo_max_rad", "rad"},
    {"ax", &DataBounds::specific_force_max_mps2, "data_bounds.specific_force_max_mps2", "m/s^2"},
    {"ay", &DataBounds::specific_force_max_mps2, "data_bounds.specific_force_max_mps2", "m/s^2"},
    {"az", &DataBounds::specific_force_max_mps2, "data_bounds.specific_force_max_mps2", "m/s^2"},
};

const QuantitySpec* quantity_spec(const char* q) {
  for (const QuantitySpec& s : kQuantities) {
    if (std::strcmp(s.quantity, q) == 0) return &s;
  }
  return nullptr;
}

}  // namespace

std::optional<QuantityBound> quantity_bound(const std::string& q, const DataBounds& b) {
  const QuantitySpec* spec = quantity_spec(q.c_str());
  if (spec == nullptr) return std::nullopt;  // t, psi (a heading may be unwrapped; the toolkit does not use it)
  return QuantityBound{b.*(spec->member), spec->key, spec->unit};
}

BoundsTally::BoundsTally(const DataBounds& bounds, std::string where) : bounds_(bounds), where_(std::move(where)) {}

BoundsTally::BoundsTally(const Vehicle& v)
    : BoundsTally(v.data_bounds, v.file.empty() ? "vehicle " + v.name : "vehicle file " + v.file) {}

bool BoundsTally::fits(const char* quantity, double t_s, double value) const {
  if (!std::isfinite(value) || !std::isfinite(t_s)) return false;
  const QuantitySpec* spec = quantity_spec(quantity);
  return spec == nullptr || std::fabs(value) <= bounds_.*(spec->member);
}

bool BoundsTally::within(const std::string& channel, const std::string& field, const std::string& quantity, double t_s,
                         double value, std::int64_t event) {
  if (fits(quantity.c_str(), t_s, value)) return true;
  count(channel, field, quantity, t_s, value, event);
  return false;
}

void BoundsTally::count(const std::string& channel, const std::string& field, const std::string& quantity, double t_s,
                        double value, std::int64_t event) {
  const std::optional<QuantityBound> bound = quantity_bound(quantity, bounds_);
  for (Entry& e : entries_) {
    if (e.channel == channel && e.field == field) {
      ++e.count;
      return;
    }
  }
  Entry e;
  e.channel = channel;
  e.field = field;
  e.quantity = quantity;
  e.count = 1;
  e.first_t_s = t_s;
  e.first_value = value;
  e.first_event = event;
  if (std::isfinite(value) && std::isfinite(t_s)) e.bound = bound;  // else: counted as not finite
  entries_.push_back(std::move(e));
}

std::uint64_t BoundsTally::samples() const {
  std::uint64_t n = 0;
  for (const Entry& e : entries_) n += e.count;
  return n;
}

const BoundsTally::Entry& BoundsTally::earliest() const {
  const Entry* best = &entries_.front();
  for (const Entry& e : entries_) {
    // A sample whose time is not finite sorts first: its place in time is unknown.
    const double t = std::isfinite(e.first_t_s) ? e.first_t_s : -INFINITY;
    const double b = std::isfinite(best->first_t_s) ? best->first_t_s : -INFINITY;
    if (t < b) best = &e;
  }
  return *best;
}

std::string BoundsTally::name(const Entry& e) {
  if (e.channel.empty()) return e.field;
  return e.channel + " " + e.field + (e.field == e.quantity ? "" : " (" + e.quantity + ")");
}

std::string BoundsTally::text(const Entry& e) {
  const std::string samples = std::to_string(e.count) + (e.count == 1 ? " sample " : " samples ");
  const std::string first = e.count == 1 ? "" : "the first ";
  if (!e.bound) {
    return name(e) + ": " + samples + "not finite (value or time), " + first + number(e.first_value, "%g") + " " +
           at_time(e);
  }
  return name(e) + ": " + samples + "beyond the physical bound " + with_unit(e.bound->value, e.bound) + " (" +
         e.bound->key + "), " + first + with_unit(e.first_value, e.bound) + " " + at_time(e);
}

std::string BoundsTally::text() const {
  std::string out;
  for (const Entry& e : entries_) out += (out.empty() ? "" : "; ") + text(e);
  const std::uint64_t n = samples();
  const std::string messages =
      messages_ == 0 ? "" : std::to_string(messages_) + (messages_ == 1 ? " message with " : " messages with ");
  return messages + std::to_string(n) + (n == 1 ? " sample" : " samples") + " beyond the physical bounds of " + where_ +
         ": " + out;
}

std::string BoundsTally::refusal() const {
  const Entry& e = earliest();
  std::string first;
  if (!e.bound) {
    first = name(e) + " = " + number(e.first_value, "%g") + " " + at_time(e) + " is not a finite number";
  } else {
    first = name(e) + " = " + with_unit(e.first_value, e.bound) + " " + at_time(e) + " exceeds the physical bound " +
            with_unit(e.bound->value, e.bound) + " (" + where_ + ", bound " + e.bound->key + ")";
  }
  return first + "; " + text();
}

OrderedJson BoundsTally::json() const {
  OrderedJson j;
  j["messages"] = messages_;
  j["samples"] = samples();
  j["bounds"] = where_;
  OrderedJson& channels = j["channels"] = OrderedJson::array();
  for (const Entry& e : entries_) {
    OrderedJson c;
    c["channel"] = e.channel;
    c["field"] = e.field;
    c["quantity"] = e.quantity;
    c["count"] = e.count;
    if (e.bound) {
      c["bound"] = e.bound->value;
      c["key"] = e.bound->key;
      c["unit"] = e.bound->unit;
    }
    c["first_t_s"] = e.first_t_s;
    c["first_value"] = e.first_value;
    c["first_event"] = e.first_event;
    channels.push_back(std::move(c));
  }
  return j;
}

}  // namespace nimble
