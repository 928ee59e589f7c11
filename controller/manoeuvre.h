#pragma once
/// Manoeuvres of the Delfly Nimble identification and validation flights
/// (thesis Section 7.2), defined in YAML as a sequence of segments, and the
/// player that turns one into attitude and throttle set-points over time.
///
/// Segment kinds (file format and exact widths: controller/README.md):
///  - hold:        constant roll/pitch set-point for duration_s
///  - doublet:     main frequency f: two pulses of width 1/(2 f) each, total 1/f,
///                 values offset + s A, offset - s A; s = sign, default -1 (negative first)
///  - one_one_two: unit width u = 1/(2 f) with f the main frequency of the short
///                 pulses: pulses u, u, 2 u with signs s, -s, s; the long pulse has
///                 main frequency f / 2; total 4 u = 2 / f
///  - ramp:        linear from from_deg to to_deg over duration_s on one axis
/// Throttle: set-point = trim + segment delta_throttle_pct; during segments that
/// apply it, the manoeuvre's throttle factor THRF = 1/cos(max |roll set-point|)
/// (thesis Eq 7.1 / paper Eq 29) multiplies it, so at zero offset
/// delta_t = trim_throttle_pct (THRF - 1).

#include <cstdint>
#include <string>
#include <vector>

#include "controller/attitude_controller.h"
#include "core/config.h"

namespace nimble {

/// Kind of a manoeuvre segment.
enum class SegmentKind { kHold, kDoublet, kOneOneTwo, kRamp };
/// Attitude axis a segment's pulses or ramp act on.
enum class Axis { kRoll, kPitch };

/// YAML name of a segment kind ("hold", "doublet", "one_one_two", "ramp").
std::string to_string(SegmentKind kind);
/// YAML name of an axis ("roll", "pitch").
std::string to_string(Axis axis);

/// One segment of a manoeuvre. Angles in rad internally (degrees in the file).
struct Segment {
  SegmentKind kind = SegmentKind::kHold;  ///< what the segment commands
  std::string name;                       ///< name from the file or "<kind>_<index>"
  Axis axis = Axis::kRoll;                ///< axis of the doublet, 112 or ramp
  double duration_s = 0.0;                ///< length [s]; derived for doublet (1/f) and 112 (2/f)
  double roll_rad = 0.0;                  ///< roll set-point, or the offset of a roll doublet/112 [rad]
  double pitch_rad = 0.0;                 ///< pitch set-point, or the offset of a pitch doublet/112 [rad]
  double amplitude_rad = 0.0;             ///< pulse amplitude of a doublet/112 [rad], > 0
  double main_frequency_hz = 0.0;         ///< doublet: its main frequency; 112: that of the short pulses [Hz]
  int sign = -1;                          ///< sign of the first pulse of a doublet/112, -1 or +1
  double ramp_from_rad = 0.0;             ///< ramp start value [rad]
  double ramp_to_rad = 0.0;               ///< ramp end value [rad]
  double delta_throttle_pct = 0.0;        ///< throttle offset from trim before the factor [%]
  bool apply_throttle_factor = false;     ///< multiply the throttle by the manoeuvre's THRF
  std::string gain_set;                   ///< roll gain set during this segment

  /// Width of one unit pulse [s]: 1/(2 f) for doublet and 112, 0 otherwise.
  double pulse_width_s() const;
  /// Roll and pitch set-points [rad] at `t_local_s` seconds into the segment.
  void attitude_at(double t_local_s, double& roll_rad, double& pitch_rad) const;
  /// Largest |roll set-point| the segment commands [rad].
  double max_abs_roll_rad() const;
  /// Largest |pitch set-point| the segment commands [rad].
  double max_abs_pitch_rad() const;
};

/// A named sequence of segments.
struct Manoeuvre {
  std::string name;                  ///< manoeuvre name (published in attitude_setpoint_t.manoeuvre)
  std::string source;                ///< where the manoeuvre comes from (thesis section, figure)
  std::string file;                  ///< file it was loaded from (empty if built in code)
  std::string gain_set = "fast";     ///< default roll gain set of the segments
  bool throttle_factor_auto = true;  ///< THRF = 1/cos(max |roll set-point|)
  /// `throttle_factor: setpoint`: THRF follows the roll set-point, 1/cos(phi_sp(t)), in the
  /// segments that apply it (thesis Eq 7.1 read with the set-point of the moment, Figs 7.1-7.4).
  bool throttle_factor_from_setpoint = false;
  double throttle_factor = 1.0;   ///< THRF applied in segments that apply it [-], >= 1 (the largest, with setpoint)
  std::vector<Segment> segments;  ///< flown in order, from t = 0

  /// Sum of the segment durations [s].
  double duration_s() const;
  /// Largest |roll set-point| over all segments [rad].
  double max_abs_roll_rad() const;
};

/// THRF = 1 / cos(max_abs_roll_rad) (thesis Eq 7.1, paper Eq 29) [-].
/// @throws std::invalid_argument unless 0 <= max_abs_roll_rad < pi/2.
double throttle_factor_for(double max_abs_roll_rad);

/// Largest roll or pitch set-point a manoeuvre may command [rad]: 60 deg, the
/// onboard set-point limit.
constexpr double kManoeuvreAngleLimitRad = 1.0471975511965976;

/// Reads a manoeuvre from a mapping (the root of a manoeuvre file).
/// @throws ConfigError naming file, key path (e.g. "segments[2].amplitude_deg"),
///         value and problem: unknown key or kind, missing key, non-positive
///         duration or frequency, |set-point| beyond 60 deg, empty segment list, ...
Manoeuvre manoeuvre_from_config(ConfigMap& map);

/// Loads a manoeuvre file (rig_configs/manoeuvres/*.yaml).
/// @throws ConfigError as manoeuvre_from_config.
Manoeuvre load_manoeuvre(const std::string& file);

/// Checks that every gain set the manoeuvre names exists in `config`.
/// @throws ConfigError naming the manoeuvre file, the key and the unknown name.
void check_gain_sets(const Manoeuvre& manoeuvre, const ControllerConfig& config);

/// Set-point of a manoeuvre at one instant; the fields of attitude_setpoint_t.
struct Setpoint {
  double roll_sp_rad = 0.0;         ///< roll set-point [rad]
  double pitch_sp_rad = 0.0;        ///< pitch set-point [rad]
  double throttle_pct = 0.0;        ///< throttle before tilt compensation [% of full scale, 0..100]
  double throttle_factor = 1.0;     ///< THRF in this segment, 1 where not applied [-]
  double delta_throttle_pct = 0.0;  ///< model delta_t = throttle_pct * throttle_factor - trim [%]
  int segment_index = -1;           ///< 0-based segment index; -1 outside the manoeuvre
  std::string segment_name;         ///< empty outside the manoeuvre
  std::string manoeuvre;            ///< manoeuvre name; empty outside the manoeuvre
  std::string gain_set;             ///< roll gain set requested
  bool active = false;              ///< t inside [0, duration)
};

/// Plays a manoeuvre: set-point as a function of time since its start.
class ManoeuvrePlayer {
 public:
  /// @throws std::invalid_argument unless 0 < trim_throttle_pct < 100 and every
  ///         segment's trim + delta_throttle_pct lies in [0, 100] (names the segment).
  ManoeuvrePlayer(Manoeuvre manoeuvre, double trim_throttle_pct);

  /// Set-point at `t_s` seconds after the start [s]. Outside [0, duration) it is
  /// the idle hover set-point (level, trim throttle, factor 1, index -1). Never throws.
  Setpoint at(double t_s) const;
  /// Length of the manoeuvre [s].
  double duration_s() const { return duration_s_; }
  /// Start time of segment `index` [s]; duration_s() for index == size.
  double segment_start_s(std::size_t index) const { return starts_.at(index); }
  /// The manoeuvre being played.
  const Manoeuvre& manoeuvre() const { return manoeuvre_; }
  /// Trim throttle [%].
  double trim_throttle_pct() const { return trim_throttle_pct_; }

 private:
  Manoeuvre manoeuvre_;
  double trim_throttle_pct_;
  std::vector<double> starts_;  // segment start times, plus the end
  double duration_s_ = 0.0;
};

}  // namespace nimble
