#include "controller/manoeuvre.h"

#include <algorithm>
#include <cmath>
#include <sstream>
#include <stdexcept>
#include <utility>

#include "core/constants.h"
#include "core/config.h"

namespace nimble {
namespace {

constexpr double kDegToRad = kPi / 180.0;
constexpr double kLimitDeg = 60.0;            // onboard roll set-point limit
constexpr double kMaxMainFrequencyHz = 50.0;  // pulses of at least 10 ms (5 control steps at 512 Hz)

const Range kAngleDeg = Range::closed(-kLimitDeg, kLimitDeg);
const Range kAmplitudeDeg{0.0, kLimitDeg, true, false};
const Range kFrequencyHz{0.0, kMaxMainFrequencyHz, true, false};
const Range kDeltaThrottlePct = Range::closed(-100.0, 100.0);
// THRF of a 60 deg set-point is 2.
const Range kThrottleFactor = Range::closed(1.0, 2.0);

Axis axis_from(ConfigMap& seg, bool required) {
  if (!required && !seg.has("axis")) return Axis::kRoll;
  return seg.get_enum("axis", {"roll", "pitch"}) == "roll" ? Axis::kRoll : Axis::kPitch;
}

/// The base (offset) of `axis` plus and minus the amplitude must stay within the limit.
void check_pulse_limit(ConfigMap& seg, const Segment& s) {
  const double base = s.axis == Axis::kRoll ? s.roll_rad : s.pitch_rad;
  if (std::fabs(base) + s.amplitude_rad > kManoeuvreAngleLimitRad + 1e-12) {
    seg.fail("amplitude_deg", "offset " + general_text(base / kDegToRad) +
                                  " deg plus/minus the amplitude exceeds the " + general_text(kLimitDeg) +
                                  " deg set-point limit");
  }
}

Segment segment_from(ConfigMap& seg, std::size_t index, const std::string& default_gain_set) {
  Segment s;
  const std::string kind = seg.get_enum("kind", {"hold", "doublet", "one_one_two", "ramp"});
  s.kind = kind == "hold"      ? SegmentKind::kHold
           : kind == "doublet" ? SegmentKind::kDoublet
           : kind == "ramp"    ? SegmentKind::kRamp
                               : SegmentKind::kOneOneTwo;
  s.name = seg.get_string_or("name", kind + "_" + std::to_string(index));
  s.delta_throttle_pct = seg.get_double_or("delta_throttle_pct", 0.0, kDeltaThrottlePct);
  s.gain_set = seg.get_string_or("gain_set", default_gain_set);

  switch (s.kind) {
    case SegmentKind::kHold:
      s.duration_s = seg.get_double("duration_s", Range::positive());
      s.roll_rad = seg.get_double_or("roll_deg", 0.0, kAngleDeg) * kDegToRad;
      s.pitch_rad = seg.get_double_or("pitch_deg", 0.0, kAngleDeg) * kDegToRad;
      break;
    case SegmentKind::kDoublet:
    case SegmentKind::kOneOneTwo: {
      if (seg.has("duration_s")) {
        seg.fail("duration_s", "the duration of a " + kind + " follows from main_frequency_hz (" +
                                   (s.kind == SegmentKind::kDoublet ? "1/f" : "2/f") +
                                   "); add a hold segment for time after it");
      }
      s.axis = axis_from(seg, false);
      s.roll_rad = seg.get_double_or("roll_deg", 0.0, kAngleDeg) * kDegToRad;
      s.pitch_rad = seg.get_double_or("pitch_deg", 0.0, kAngleDeg) * kDegToRad;
      s.amplitude_rad = seg.get_double("amplitude_deg", kAmplitudeDeg) * kDegToRad;
      s.main_frequency_hz = seg.get_double("main_frequency_hz", kFrequencyHz);
      if (seg.has("sign")) {
        const long long sign = seg.get_int("sign", Range::closed(-1.0, 1.0));
        if (sign == 0) seg.fail("sign", "must be -1 or +1");
        s.sign = static_cast<int>(sign);
      }
      check_pulse_limit(seg, s);
      s.duration_s = (s.kind == SegmentKind::kDoublet ? 2.0 : 4.0) * s.pulse_width_s();
      break;
    }
    case SegmentKind::kRamp: {
      s.axis = axis_from(seg, true);
      const char* own = s.axis == Axis::kRoll ? "roll_deg" : "pitch_deg";
      if (seg.has(own)) {
        seg.fail(own, std::string("a ramp on ") + to_string(s.axis) + " takes its values from from_deg and to_deg");
      }
      s.duration_s = seg.get_double("duration_s", Range::positive());
      s.ramp_from_rad = seg.get_double("from_deg", kAngleDeg) * kDegToRad;
      s.ramp_to_rad = seg.get_double("to_deg", kAngleDeg) * kDegToRad;
      if (s.axis == Axis::kRoll) {
        s.pitch_rad = seg.get_double_or("pitch_deg", 0.0, kAngleDeg) * kDegToRad;
      } else {
        s.roll_rad = seg.get_double_or("roll_deg", 0.0, kAngleDeg) * kDegToRad;
      }
      break;
    }
  }
  const bool level_hold = s.kind == SegmentKind::kHold && s.roll_rad == 0.0 && s.pitch_rad == 0.0;
  s.apply_throttle_factor = seg.has("apply_throttle_factor") ? seg.get_bool("apply_throttle_factor") : !level_hold;
  seg.finish();
  return s;
}

}  // namespace

std::string to_string(SegmentKind kind) {
  switch (kind) {
    case SegmentKind::kHold: return "hold";
    case SegmentKind::kDoublet: return "doublet";
    case SegmentKind::kOneOneTwo: return "one_one_two";
    case SegmentKind::kRamp: return "ramp";
  }
  return "?";
}

std::string to_string(Axis axis) { return axis == Axis::kRoll ? "roll" : "pitch"; }

double Segment::pulse_width_s() const {
  if (kind == SegmentKind::kDoublet || kind == SegmentKind::kOneOneTwo) return 0.5 / main_frequency_hz;
  return 0.0;
}

void Segment::attitude_at(double t, double& roll, double& pitch) const {
  roll = roll_rad;
  pitch = pitch_rad;
  double value = 0.0;
  switch (kind) {
    case SegmentKind::kHold: return;
    case SegmentKind::kDoublet: {
      const double u = pulse_width_s();
      value = (t < u ? sign : -sign) * amplitude_rad;
      break;
    }
    case SegmentKind::kOneOneTwo: {
      const double u = pulse_width_s();
      value = (t < u ? sign : t < 2.0 * u ? -sign : sign) * amplitude_rad;
      break;
    }
    case SegmentKind::kRamp: {
      const double frac = std::clamp(t / duration_s, 0.0, 1.0);
      const double v = ramp_from_rad + (ramp_to_rad - ramp_from_rad) * frac;
      (axis == Axis::kRoll ? roll : pitch) = v;
      return;
    }
  }
  (axis == Axis::kRoll ? roll : pitch) += value;
}

double Segment::max_abs_roll_rad() const {
  if (axis == Axis::kRoll) {
    if (kind == SegmentKind::kDoublet || kind == SegmentKind::kOneOneTwo) return std::fabs(roll_rad) + amplitude_rad;
    if (kind == SegmentKind::kRamp) return std::max(std::fabs(ramp_from_rad), std::fabs(ramp_to_rad));
  }
  return std::fabs(roll_rad);
}

double Segment::max_abs_pitch_rad() const {
  if (axis == Axis::kPitch) {
    if (kind == SegmentKind::kDoublet || kind == SegmentKind::kOneOneTwo) return std::fabs(pitch_rad) + amplitude_rad;
    if (kind == SegmentKind::kRamp) return std::max(std::fabs(ramp_from_rad), std::fabs(ramp_to_rad));
  }
  return std::fabs(pitch_rad);
}

double Manoeuvre::duration_s() const {
  double total = 0.0;
  for (const auto& s : segments) total += s.duration_s;
  return total;
}

double Manoeuvre::max_abs_roll_rad() const {
  double m = 0.0;
  for (const auto& s : segments) m = std::max(m, s.max_abs_roll_rad());
  return m;
}

double throttle_factor_for(double max_abs_roll_rad) {
  if (!(std::isfinite(max_abs_roll_rad) && max_abs_roll_rad >= 0.0 && max_abs_roll_rad < 0.5 * kPi)) {
    throw std::invalid_argument("throttle_factor_for: max |roll set-point| must be in [0, pi/2) rad, got " +
                                general_text(max_abs_roll_rad));
  }
  return 1.0 / std::cos(max_abs_roll_rad);
}

Manoeuvre manoeuvre_from_config(ConfigMap& map) {
  Manoeuvre m;
  m.file = map.file();
  m.name = map.get_string("name");
  m.source = map.get_string("source");
  m.gain_set = map.get_string_or("gain_set", m.gain_set);

  bool factor_auto = true;
  double factor = 1.0;
  if (map.has("throttle_factor")) {
    const YAML::Node node = map.get_node("throttle_factor");
    if (node.IsScalar() && node.Scalar() == "setpoint") {
      m.throttle_factor_from_setpoint = true;
    } else if (!(node.IsScalar() && node.Scalar() == "auto")) {
      factor = map.get_double("throttle_factor", kThrottleFactor);
      factor_auto = false;
    }
  }

  const YAML::Node list = map.get_node("segments");
  if (!list.IsSequence() || list.size() == 0) map.fail("segments", "must be a non-empty list of segments");
  for (std::size_t i = 0; i < list.size(); ++i) {
    ConfigMap seg(list[i], map.file(), map.key_path("segments") + "[" + std::to_string(i) + "]");
    m.segments.push_back(segment_from(seg, i, m.gain_set));
  }
  map.finish();

  m.throttle_factor_auto = factor_auto;
  m.throttle_factor = factor_auto ? throttle_factor_for(m.max_abs_roll_rad()) : factor;
  return m;
}

Manoeuvre load_manoeuvre(const std::string& file) {
  ConfigMap map = ConfigMap::load_file(file);
  return manoeuvre_from_config(map);
}

void check_gain_sets(const Manoeuvre& manoeuvre, const ControllerConfig& config) {
  std::string known;
  for (const auto& item : config.roll_gain_sets) known += (known.empty() ? "" : ", ") + item.first;
  for (std::size_t i = 0; i < manoeuvre.segments.size(); ++i) {
    const std::string& name = manoeuvre.segments[i].gain_set;
    if (config.roll_gain_sets.count(name) == 0) {
      const bool inherited = name == manoeuvre.gain_set;
      throw ConfigError(manoeuvre.file, inherited ? "gain_set" : "segments[" + std::to_string(i) + "].gain_set", name,
                        "unknown gain set (known: " + known + ")");
    }
  }
}

ManoeuvrePlayer::ManoeuvrePlayer(Manoeuvre manoeuvre, double trim_throttle_pct)
    : manoeuvre_(std::move(manoeuvre)), trim_throttle_pct_(trim_throttle_pct) {
  if (!(std::isfinite(trim_throttle_pct) && trim_throttle_pct > 0.0 && trim_throttle_pct < 100.0)) {
    throw std::invalid_argument("manoeuvre player: trim_throttle_pct must be in (0, 100), got " +
                                general_text(trim_throttle_pct));
  }
  if (manoeuvre_.segments.empty()) {
    throw std::invalid_argument("manoeuvre player: manoeuvre '" + manoeuvre_.name + "' has no segments");
  }
  double t = 0.0;
  for (std::size_t i = 0; i < manoeuvre_.segments.size(); ++i) {
    const Segment& s = manoeuvre_.segments[i];
    const double throttle = trim_throttle_pct_ + s.delta_throttle_pct;
    if (throttle < 0.0 || throttle > 100.0) {
      throw std::invalid_argument("manoeuvre '" + manoeuvre_.name + "' segment " + std::to_string(i) + " '" + s.name +
                                  "': trim " + general_text(trim_throttle_pct_) + " % + delta_throttle_pct " +
                                  general_text(s.delta_throttle_pct) + " % is outside [0, 100] %");
    }
    if (!(std::isfinite(s.duration_s) && s.duration_s > 0.0)) {
      throw std::invalid_argument("manoeuvre '" + manoeuvre_.name + "' segment " + std::to_string(i) + " '" + s.name +
                                  "': duration must be > 0 s, got " + general_text(s.duration_s));
    }
    starts_.push_back(t);
    t += s.duration_s;
  }
  starts_.push_back(t);
  duration_s_ = t;
}

Setpoint ManoeuvrePlayer::at(double t_s) const {
  Setpoint sp;
  sp.gain_set = manoeuvre_.gain_set;
  sp.throttle_pct = trim_throttle_pct_;
  if (!(std::isfinite(t_s) && t_s >= 0.0 && t_s < duration_s_)) return sp;

  // Last segment whose start is <= t.
  const auto it = std::upper_bound(starts_.begin(), starts_.end() - 1, t_s);
  const std::size_t index = static_cast<std::size_t>(it - starts_.begin()) - 1;
  const Segment& s = manoeuvre_.segments[index];
  s.attitude_at(t_s - starts_[index], sp.roll_sp_rad, sp.pitch_sp_rad);
  sp.throttle_pct = std::clamp(trim_throttle_pct_ + s.delta_throttle_pct, 0.0, 100.0);
  sp.throttle_factor = !s.apply_throttle_factor                   ? 1.0
                       : manoeuvre_.throttle_factor_from_setpoint ? throttle_factor_for(std::fabs(sp.roll_sp_rad))
                                                                  : manoeuvre_.throttle_factor;
  sp.delta_throttle_pct = sp.throttle_pct * sp.throttle_factor - trim_throttle_pct_;
  sp.segment_index = static_cast<int>(index);
  sp.segment_name = s.name;
  sp.manoeuvre = manoeuvre_.name;
  sp.gain_set = s.gain_set;
  sp.active = true;
  return sp;
}

}  // namespace nimble
