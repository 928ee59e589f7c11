#include "detection_power/record_length.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "controller/manoeuvre.h"
#include "core/output_file.h"
#include "core/yaml_input.h"

namespace nimble::detection_power {
namespace {

std::string manoeuvre_file_of(const Scenario& scenario) {
  return manoeuvre_file(scenario, true, "a power flight repeats the scenario's manoeuvre");
}

/// The manoeuvre file's segments `repetitions` times, with a level hold of `pad_s` between.
YAML::Node repeated(const YAML::Node& manoeuvre, int repetitions, double pad_s) {
  YAML::Node out = YAML::Clone(manoeuvre);
  YAML::Node segments(YAML::NodeType::Sequence);
  for (int r = 0; r < repetitions; ++r) {
    if (r > 0 && pad_s > 0.0) {
      YAML::Node hold(YAML::NodeType::Map);
      hold["kind"] = "hold";
      hold["name"] = "repeat_hover_" + std::to_string(r);
      hold["duration_s"] = pad_s;
      segments.push_back(hold);
    }
    for (const auto& s : manoeuvre["segments"]) {
      YAML::Node seg = YAML::Clone(s);
      if (r > 0 && seg["name"]) seg["name"] = seg["name"].as<std::string>() + "_" + std::to_string(r + 1);
      segments.push_back(seg);
    }
  }
  out["segments"] = segments;
  return out;
}

}  // namespace

double block_length_s(const Scenario& scenario) {
  const Manoeuvre m = load_manoeuvre(manoeuvre_file_of(scenario));
  return std::max(scenario.duration_s, m.duration_s());
}

RecordLength record_length(const Scenario& scenario, double length_s, const std::string& dir) {
  if (!(std::isfinite(length_s) && length_s > 0.0)) {
    throw std::invalid_argument("record length " + shortest_text(length_s) + " s: must be > 0");
  }
  RecordLength out;
  out.length_s = length_s;
  const std::string file = manoeuvre_file_of(scenario);
  const Manoeuvre manoeuvre = load_manoeuvre(file);
  out.block_s = std::max(scenario.duration_s, manoeuvre.duration_s());
  out.repetitions = std::max(1, static_cast<int>(std::ceil(length_s / out.block_s - 1e-9)));
  if (length_s != scenario.duration_s) out.overrides.push_back({"duration_s", shortest_text(length_s)});
  if (out.repetitions == 1) return out;

  const double pad_s = out.block_s - manoeuvre.duration_s();
  const std::filesystem::path path = std::filesystem::path(dir) / (std::filesystem::path(file).stem().string() + "_x" +
                                                                   std::to_string(out.repetitions) + ".yaml");
  YAML::Emitter emitter;
  emitter << repeated(load_yaml_file(file), out.repetitions, pad_s);
  write_file(path, "# " + file + " flown " + std::to_string(out.repetitions) + " times, " + shortest_text(pad_s) +
                       " s of level hover between (rig discrepancy --power)\n" + emitter.c_str() + "\n");
  out.manoeuvre_file = path.string();
  out.overrides.push_back({"manoeuvre", out.manoeuvre_file});
  return out;
}

}  // namespace nimble::detection_power
