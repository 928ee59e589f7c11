#include "reproduce/seed_values.h"

#include <cmath>
#include <filesystem>
#include <limits>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "reproduce/campaign_spec.h"
#include "scenario/scenario.h"

namespace nimble::reproduce {
namespace {

using Json = nlohmann::json;

/// A double as JSON: a number (nlohmann writes the shortest text that reads back to the same
/// double), or null for NaN, which JSON has not.
Json number(double x) { return std::isnan(x) ? Json(nullptr) : Json(x); }
double number_of(const Json& j) { return j.is_null() ? std::numeric_limits<double>::quiet_NaN() : j.get<double>(); }

Json cells_json(const CellMap& m) {
  Json j = Json::object();
  for (const auto& [k, v] : m) j[k] = number(v);
  return j;
}
CellMap cells_of(const Json& j) {
  CellMap m;
  for (auto it = j.begin(); it != j.end(); ++it) m[it.key()] = number_of(it.value());
  return m;
}

Json nested_json(const std::map<std::string, std::map<std::string, double>>& m) {
  Json j = Json::object();
  for (const auto& [row, values] : m) j[row] = cells_json(values);
  return j;
}
std::map<std::string, std::map<std::string, double>> nested_of(const Json& j) {
  std::map<std::string, std::map<std::string, double>> m;
  for (auto it = j.begin(); it != j.end(); ++it) m[it.key()] = cells_of(it.value());
  return m;
}

Json record_json(const FlightRecord& r) {
  return {{"name", r.name},           {"seed", r.seed},
          {"scenario", r.scenario},   {"log", r.log},
          {"result", r.result},       {"controlled", r.controlled},
          {"sim_s", number(r.sim_s)}, {"wall_s", number(r.wall_s)}};
}
FlightRecord record_of(const Json& j) {
  FlightRecord r;
  r.name = j.at("name").get<std::string>();
  r.seed = j.at("seed").get<std::uint64_t>();
  r.scenario = j.at("scenario").get<std::string>();
  r.log = j.at("log").get<std::string>();
  r.result = j.at("result").get<std::string>();
  r.controlled = j.at("controlled").get<bool>();
  r.sim_s = number_of(j.at("sim_s"));
  r.wall_s = number_of(j.at("wall_s"));
  return r;
}

}  // namespace

std::string seed_values_line(const SeedValues& v) {
  Json j;
  j["seed"] = v.seed;
  j["tables"] = Json::object();
  for (const auto& [id, cells] : v.tables) j["tables"][id] = cells_json(cells);
  j["identified"] = nested_json(v.identified);
  j["plant"] = nested_json(v.plant);
  j["flights"] = Json::array();
  for (const FlightRecord& r : v.flights) j["flights"].push_back(record_json(r));
  j["with"] = Json::array();
  for (const WithFlight& w : v.with) {
    j["with"].push_back({{"cells", cells_json(w.cells)},
                         {"failure", w.failure},
                         {"record", w.record ? record_json(*w.record) : Json(nullptr)}});
  }
  return j.dump();
}

SeedValues seed_values_from_line(const std::string& line) {
  try {
    const Json j = Json::parse(line);
    SeedValues v;
    v.seed = j.at("seed").get<std::uint64_t>();
    for (auto it = j.at("tables").begin(); it != j.at("tables").end(); ++it) v.tables[it.key()] = cells_of(it.value());
    v.identified = nested_of(j.at("identified"));
    v.plant = nested_of(j.at("plant"));
    for (const Json& r : j.at("flights")) v.flights.push_back(record_of(r));
    for (const Json& w : j.at("with")) {
      WithFlight f;
      f.cells = cells_of(w.at("cells"));
      f.failure = w.at("failure").get<std::string>();
      if (!w.at("record").is_null()) f.record = record_of(w.at("record"));
      v.with.push_back(std::move(f));
    }
    return v;
  } catch (const nlohmann::json::exception& e) {
    throw std::runtime_error("rig reproduce: a seed's values do not read back (" + std::string(e.what()) +
                             "): " + line.substr(0, 200));
  }
}

std::string seed_key(std::uint64_t seed) { return "seed-" + std::to_string(seed); }

std::vector<Override> flight_overrides(const CampaignOptions& o, const std::vector<Override>& own) {
  std::vector<Override> all = o.overrides;
  all.insert(all.end(), own.begin(), own.end());
  return all;
}

std::vector<std::string> override_texts(const std::vector<Override>& overrides) {
  std::vector<std::string> out;
  for (const Override& ov : overrides) out.push_back(ov.key_path + "=" + ov.value);
  return out;
}

campaign::Manifest seeds_manifest(const CampaignOptions& o, const CampaignSpec& spec) {
  namespace fs = std::filesystem;
  const auto absolute = [](const std::string& p) { return fs::absolute(p).lexically_normal().string(); };
  Json m;
  m["campaign_file"] = absolute(o.campaign_file);
  m["campaign_file_digest"] = file_digest(o.campaign_file);
  m["clock"] = o.clock;
  m["states"] = o.states;
  m["logs"] = absolute(o.work_dir);
  m["controller_digest"] = file_digest(o.controller_file);
  m["rig_digest"] = file_digest("/proc/self/exe", InputKind::kProgram);
  // Overrides on every flight: named (checked before the scenarios, so a refusal names them), and
  // in the scenarios' digests, with the content of a base file they name.
  m["overrides"] = override_texts(o.overrides);
  for (const auto& [name, scenario] : spec.flights) {
    m["scenario_digests"][name] = scenario_digest(load_scenario(scenario, o.overrides));
  }
  for (const auto& set : spec.sets) m["model_digests"][set.row] = file_digest(set.model);
  m["model_digests"]["lateral4"] = file_digest(spec.lateral4_model);
  for (const auto& [id, model] : spec.coupled_models) m["model_digests"][id] = file_digest(model);
  return campaign::Manifest{"rig reproduce thesis", m, {}};
}

std::vector<PlantCheck> plant_check(const CampaignSpec& spec, const std::vector<SeedValues>& seeds) {
  std::vector<PlantCheck> out;
  for (const auto& set : spec.sets) {
    for (const char* d : kCheckedDerivatives) {
      for (const char* method : {"equation error", "output error"}) {
        PlantCheck c;
        c.row = set.row;
        c.derivative = d;
        c.method = method;
        c.plant = seeds.front().plant.at(set.row).at(d);
        const std::string key = std::string(d) + (c.method == "output error" ? kOutputErrorSuffix : "");
        std::vector<double> x;
        c.own_sd = 0.0;
        for (const SeedValues& v : seeds) {
          x.push_back(v.identified.at(set.row).at(key));
          c.own_sd += v.identified.at(set.row).at(key + kOwnSigmaSuffix) / static_cast<double>(seeds.size());
        }
        mean_interval(x, &c.mean, &c.sd, &c.interval);
        out.push_back(c);
      }
    }
  }
  return out;
}

}  // namespace nimble::reproduce
