#include "effects/flapping_forcing.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <random>
#include <stdexcept>
#include <utility>

namespace nimble::effects {
namespace {

/// Harmonics the plant accepts from a model (the workflow fits 2).
constexpr int kMaxHarmonics = 10;

/// The range of every amplitude (N or N m): the plant file's and a model's alike.
const Range kAmplitudeRange = Range::closed(-1.0, 1.0);

/// A list of amplitudes: finite numbers of magnitude at most 1 (N or N m).
std::vector<double> read_amplitudes(ConfigMap& map, const std::string& key) {
  std::vector<double> out;
  if (!map.has(key)) {
    map.get_double_or(key, 0.0);  // mark as known
    return out;
  }
  const YAML::Node node = map.get_node(key);
  if (!node.IsSequence()) map.fail(key, "must be a list of numbers");
  for (const auto& item : node) {
    try {
      out.push_back(item.as<double>());
    } catch (const YAML::Exception&) {
      map.fail(key, "must be a list of numbers");
    }
    if (!std::isfinite(out.back()) || !kAmplitudeRange.contains(out.back())) {
      map.fail(key, "entries must be finite and at most 1 in magnitude (N or N m)");
    }
  }
  return out;
}

/// Parses "<eq>_<kind><h>" (e.g. "L_sin2") for eq L or Y, kind sin, cos or amp, h 1..kMaxHarmonics.
bool parse_harmonic(const std::string& key, char* eq, std::string* kind, int* h) {
  if (key.size() < 6 || (key[0] != 'L' && key[0] != 'Y') || key[1] != '_') return false;
  const std::string k = key.substr(2, 3);
  if (k != "sin" && k != "cos" && k != "amp") return false;
  const std::string digits = key.substr(5);
  if (digits.empty() || digits.size() > 2 || digits[0] == '0' ||
      !std::all_of(digits.begin(), digits.end(), [](char c) { return c >= '0' && c <= '9'; })) {
    return false;
  }
  const int n = std::stoi(digits);
  if (n < 1 || n > kMaxHarmonics) return false;
  *eq = key[0];
  *kind = k;
  *h = n;
  return true;
}

/// Amplitudes per harmonic of equation `eq`: hypot(sin_h, cos_h) where the section carries
/// either, otherwise <eq>_amp<h> (the workflow writes it as that same hypot), otherwise 0; as
/// many harmonics as the highest one the section names for `eq`.
std::vector<double> harmonic_amplitudes(const ModelSection& s, char eq) {
  std::map<int, double> sin_of, cos_of, amp_of;
  int highest = 0;
  for (const auto& [key, value] : s.params) {
    char e;
    std::string kind;
    int h;
    if (!parse_harmonic(key, &e, &kind, &h) || e != eq) continue;
    (kind == "sin" ? sin_of : kind == "cos" ? cos_of : amp_of)[h] = value;
    highest = std::max(highest, h);
  }
  std::vector<double> out;
  for (int h = 1; h <= highest; ++h) {
    double a = 0.0;
    if (sin_of.count(h) || cos_of.count(h)) {
      a = std::hypot(sin_of.count(h) ? sin_of[h] : 0.0, cos_of.count(h) ? cos_of[h] : 0.0);
    } else if (amp_of.count(h)) {
      a = std::fabs(amp_of[h]);
    }
    if (!kAmplitudeRange.contains(a)) {
      s.fail("harmonic " + std::to_string(h) + " of " + std::string(1, eq) + " has amplitude " + std::to_string(a) +
             ", more than 1 (N or N m), which the plant file's amplitudes may not exceed either");
    }
    out.push_back(a);
  }
  return out;
}

}  // namespace

namespace {

class FlappingForcingProcess : public EffectProcess {
 public:
  FlappingForcingProcess(const FlappingForcingConfig& config, std::vector<double> phases_roll,
                         std::vector<double> phases_side)
      : config_(config), phases_roll_(std::move(phases_roll)), phases_side_(std::move(phases_side)) {}
  void add_loads(const LoadInputs& in, double& L, double& Y) const override {
    add_flapping_forcing(config_, in.flap_phase_rad, phases_roll_, phases_side_, L, Y);
  }

 private:
  FlappingForcingConfig config_;
  std::vector<double> phases_roll_, phases_side_;
};

}  // namespace

std::unique_ptr<EffectProcess> flapping_forcing_process(const FlappingForcingConfig& config, ProcessContext& context) {
  std::uniform_real_distribution<double> phase(0.0, 2.0 * M_PI);
  std::vector<double> roll, side;
  for (std::size_t h = 0; h < config.roll_moment_amplitudes_nm.size(); ++h) roll.push_back(phase(context.rng));
  for (std::size_t h = 0; h < config.side_force_amplitudes_n.size(); ++h) side.push_back(phase(context.rng));
  if (!config.enabled) return nullptr;
  return std::make_unique<FlappingForcingProcess>(config, std::move(roll), std::move(side));
}

std::string flapping_forcing_markdown_rows(const std::string& prefix) {
  return "| `" + prefix +
         "enabled` | false | true, false | - | fly the effect (required) |\n"
         "| `" +
         prefix +
         "roll_moment_amplitudes_nm` | [] | list, each in [-1, 1] | N m | roll moment at harmonic h "
         "(entry h-1) of the flapping frequency |\n"
         "| `" +
         prefix +
         "side_force_amplitudes_n` | [] | list, each in [-1, 1] | N | side force at harmonic h "
         "(entry h-1) of the flapping frequency |\n";
}

FlappingForcingConfig flapping_forcing_from(ConfigMap& map) {
  FlappingForcingConfig c;
  c.enabled = map.get_bool("enabled");
  c.roll_moment_amplitudes_nm = read_amplitudes(map, "roll_moment_amplitudes_nm");
  c.side_force_amplitudes_n = read_amplitudes(map, "side_force_amplitudes_n");
  return c;
}

void flapping_forcing_from_model(const ModelSection& s, FlappingForcingConfig& c) {
  // The workflow regresses sin and cos of h 2 pi f t (h = 1, 2) at a fixed frequency f
  // (flapping_hz) found in the data. The plant flies harmonic h with amplitude
  // hypot(sin_h, cos_h) in roll moment and side force, phase-locked to its own flapping phase:
  // at h times the flapping frequency of the actual collective (about 16-17 Hz at trim; it
  // follows the throttle), not at flapping_hz. The phase relative to the flapping phase is not
  // identifiable from a fixed-frequency regression on a record with an arbitrary time origin,
  // so the plant keeps its seeded phases.
  s.check_keys(
      [](const std::string& k) {
        char e;
        std::string kind;
        int h;
        return k == "flapping_hz" || parse_harmonic(k, &e, &kind, &h);
      },
      "flapping_hz, <eq>_sin<h>, <eq>_cos<h>, <eq>_amp<h> for eq L or Y and h 1.." + std::to_string(kMaxHarmonics));
  c.enabled = true;
  c.roll_moment_amplitudes_nm = harmonic_amplitudes(s, 'L');
  c.side_force_amplitudes_n = harmonic_amplitudes(s, 'Y');
}

EffectSizing flapping_forcing_sizing() {
  return {"roll_moment_amplitudes_nm[0]", "N m", kAmplitudeRange,
          "every amplitude of both lists scales with the first roll amplitude",
          [](const YAML::Node& section, double size) {
            std::vector<double> roll = section_list(section, "roll_moment_amplitudes_nm");
            std::vector<double> side = section_list(section, "side_force_amplitudes_n");
            if (roll.empty() || roll[0] == 0.0) {
              throw std::invalid_argument("the scenario has no first roll amplitude to scale from");
            }
            const double k = size / roll[0];
            for (auto& a : roll) a = companion_within("roll_moment_amplitudes_nm", k * a, kAmplitudeRange);
            for (auto& a : side) a = companion_within("side_force_amplitudes_n", k * a, kAmplitudeRange);
            const auto list = [](const std::vector<double>& values) {
              std::string out = "[";
              for (std::size_t i = 0; i < values.size(); ++i) out += (i ? "," : "") + shortest_text(values[i]);
              return out + "]";
            };
            return std::vector<EffectValue>{{"roll_moment_amplitudes_nm", list(roll)},
                                            {"side_force_amplitudes_n", list(side)}};
          }};
}

Effect flapping_forcing_effect() {
  Effect e;
  std::vector<EffectColumn> columns;
  for (const char* eq : {"L", "Y"}) {
    for (const char* h : {"1", "2"}) {
      const std::string arg = std::string(h) == "1" ? "2 pi f t" : "4 pi f t";
      columns.push_back({eq, std::string(eq) + "_sin" + h, "sin(" + arg + ")", ColumnForm::kHarmonic});
      columns.push_back({eq, std::string(eq) + "_cos" + h, "cos(" + arg + ")", ColumnForm::kHarmonic});
    }
  }
  e.definition = {"flapping_forcing",
                  "sin and cos of h 2 pi f t (h = 1, 2) in roll moment and side force: periodic forcing at the "
                  "flapping frequency f, scanned over 10-25 Hz on data low-passed above the band",
                  {},
                  columns,
                  Scan::kFrequency,
                  Signature::kNone,
                  EffectivenessChange::kNone,
                  "plant.effects.flapping_forcing: amplitude hypot(sin_h, cos_h) at harmonic h of the plant's "
                  "flapping phase"};
  e.from_model = config_from_model(flapping_forcing_from_model);
  e.plant.load = [](ConfigMap& m, EffectsConfig& fx) { fx.get<FlappingForcingConfig>() = flapping_forcing_from(m); };
  e.plant.markdown_rows = flapping_forcing_markdown_rows;
  e.plant.make = [](const EffectsConfig& fx, ProcessContext& c) {
    return flapping_forcing_process(fx.get<FlappingForcingConfig>(), c);
  };
  e.plant.enabled = [](const EffectsConfig& fx) { return fx.get<FlappingForcingConfig>().enabled; };
  e.plant.sizing = flapping_forcing_sizing;
  return e;
}

}  // namespace nimble::effects
