#pragma once
/// The one check of recorded numbers against the vehicle's physical bounds (Vehicle::data_bounds,
/// the vehicle file's `data_bounds` section): every reader that turns flight data or log messages
/// into numbers (the analyses, `rig export`, the MCAP export, the Python module, the live view)
/// asks BoundsTally::within() of each bounded sample, and names what it found through the same
/// text: the channel, the field, the time and the count of samples beyond the bounds.
///
/// A quantity is one of the identification toolkit's channel names (p, q, r, u, v, w, phi, theta,
/// phi_sp, delta_f, delta_f_cmd, delta_t, delta_d, delta_w, ax, ay, az; ident/flight_data.h); a
/// log message's fields map onto them in contract/message_bounds.h. A quantity without a bound
/// (psi, a heading may be unwrapped) is checked for finiteness only.

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json_fwd.hpp>

#include "core/vehicle.h"

namespace nimble {

/// The bound of one quantity: its value, its key in the vehicle file
/// ("data_bounds.rate_max_radps") and its unit ("rad/s").
struct QuantityBound {
  double value = DataBounds::kNone;
  std::string key;
  std::string unit;
};

/// The bound of `quantity` in `bounds`; nullopt for a quantity without one (t, psi, anything
/// else: finiteness only).
std::optional<QuantityBound> quantity_bound(const std::string& quantity, const DataBounds& bounds);

/// Samples beyond the vehicle's bounds (or not finite), counted by channel and field.
class BoundsTally {
 public:
  /// One channel and field with samples beyond its bound.
  struct Entry {
    std::string channel;   ///< LCM channel (TRUTH), or "" for a record's column
    std::string field;     ///< message field ("omega_body_radps[0]"), or the column ("p")
    std::string quantity;  ///< the bounded quantity ("p")
    std::uint64_t count = 0;
    double first_t_s = 0.0;              ///< time of the first such sample [s] (may itself be not finite)
    double first_value = 0.0;            ///< its value
    std::int64_t first_event = -1;       ///< its log event number (-1: not from a log)
    std::optional<QuantityBound> bound;  ///< nullopt: a quantity without a bound (not finite)
  };

  /// `where` names the bounds in messages: "vehicle file rig_configs/vehicles/nimble_no_wifi.yaml".
  BoundsTally(const DataBounds& bounds, std::string where);
  /// The bounds of `vehicle`, named by its file (or its name when built in code).
  explicit BoundsTally(const Vehicle& vehicle);

  /// The one check: true if `value` and its time `t_s` are finite and `value` is within the bound of
  /// `quantity`; otherwise counts it under `channel`/`field` and returns false.
  bool within(const std::string& channel, const std::string& field, const std::string& quantity, double t_s,
              double value, std::int64_t event = -1);
  /// within() in two steps, for a reader that names a sample only when it does not fit: fits()
  /// judges (true: finite and within the bound), count() counts a sample that did not fit.
  bool fits(const char* quantity, double t_s, double value) const;
  void count(const std::string& channel, const std::string& field, const std::string& quantity, double t_s,
             double value, std::int64_t event = -1);

  /// A reader of messages counts each message it leaves out for samples beyond (text() names them).
  void count_message() { ++messages_; }
  std::uint64_t messages() const { return messages_; }

  bool empty() const { return entries_.empty(); }
  /// Samples counted over every channel and field.
  std::uint64_t samples() const;
  /// Every channel and field with samples beyond, in the order first met.
  const std::vector<Entry>& entries() const { return entries_; }
  /// The entry of the earliest sample beyond (by time; ties: the first met). Not on an empty tally.
  const Entry& earliest() const;
  const std::string& where() const { return where_; }

  /// "TRUTH omega_body_radps[0] (p)" or "p": how an entry names its channel and field.
  static std::string name(const Entry& e);
  /// One entry for people: "TRUTH omega_body_radps[0] (p): 2 samples beyond the physical bound
  /// 50 rad/s (data_bounds.rate_max_radps), the first 1.2e+147 rad/s at t = 3.4121 s (event 812)".
  static std::string text(const Entry& e);
  /// Every entry: "[M messages with ]N samples beyond the physical bounds of <where>: <entry>; <entry>".
  std::string text() const;
  /// The refusal of a record or log: the earliest sample beyond, then the counts:
  /// "p = 1.2e+147 rad/s at t = 3.4121 s exceeds the physical bound 50 rad/s (vehicle file F,
  /// bound data_bounds.rate_max_radps); N samples beyond the bounds: <entry>; <entry>".
  std::string refusal() const;
  /// The "beyond_bounds" object of a --json report: messages, samples, bounds, and per entry channel,
  /// field, quantity, count, bound, key, unit, first_t_s, first_value (null: not finite), first_event.
  nlohmann::ordered_json json() const;

 private:
  DataBounds bounds_;
  std::string where_;
  std::vector<Entry> entries_;
  std::uint64_t messages_ = 0;
};

}  // namespace nimble
