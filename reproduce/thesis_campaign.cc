#include "reproduce/thesis_campaign.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <set>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "controller/attitude_controller.h"
#include "core/config.h"
#include "core/model.h"
#include "core/output_file.h"
#include "core/vehicle.h"
#include "core/yaml_input.h"
#include "ident/closed_loop.h"
#include "ident/flight_sensing.h"
#include "ident/identify.h"
#include "ident/plots.h"
#include "ident/rig_log.h"
#include "ident/validate.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"
#include "reproduce/campaign_spec.h"
#include "reproduce/seed_values.h"
#include "reproduce/structure_tables.h"
#include "campaign/result_files.h"
#include "estimator/sensing_config.h"
#include "scenario/scenario.h"
#include "plots/gnuplot.h"

namespace nimble::reproduce {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// A flown flight: its log and the figures of its summary.
struct Flown {
  FlightRecord record;
  ident::SmoothingOptions smoothing;  ///< the smoother's model: the flight's own sensing (states smoothed)
  double range_p = 0, range_v = 0, range_phi = 0;
};

/// The smoother's model for a flight flown with `scenario`: its own sensing and IMU filtering.
ident::SmoothingOptions smoothing_of(const Scenario& scenario) {
  ConfigMap section = scenario.section("sensing");
  return ident::smoothing_options(sensing_config_from(section));
}

Flown fly(const CampaignOptions& o, std::uint64_t seed, const std::string& name, const std::string& scenario,
          const std::vector<Override>& own) {
  const std::vector<Override> overrides = flight_overrides(o, own);
  Flown f;
  f.record.name = name;
  f.record.seed = seed;
  f.record.scenario = scenario;
  f.record.log = (fs::path(o.work_dir) / fmt::format("{}_seed{}.lcmlog", name, seed)).string();
  const auto t0 = Clock::now();
  if (o.clock == "inprocess") {
    launcher::RunOptions ro;
    ro.scenario_file = scenario;
    ro.overrides = overrides;
    ro.clock = "inprocess";
    ro.seed = seed;
    ro.progress = false;
    ro.print_summary = false;
    const launcher::RunPlan plan = launcher::load_run_plan(ro);
    launcher::InprocessOptions io;
    io.log_file = f.record.log;
    const launcher::RunReport report = launcher::fly_inprocess(plan, io);
    if (o.states == "smoothed") f.smoothing = smoothing_of(plan.scenario);
    f.record.result = report.verdict.text;
    f.record.controlled = report.verdict.controlled;
    f.record.sim_s = report.sim_time_s;
    f.range_p = report.flight.max_p - report.flight.min_p;
    f.range_v = report.flight.max_v - report.flight.min_v;
    f.range_phi = report.flight.max_phi - report.flight.min_phi;
  } else {
    const std::string json = (fs::path(o.work_dir) / fmt::format("{}_seed{}.json", name, seed)).string();
    std::string cmd = "'" + o.rig_exe + "' run '" + scenario + "' --clock " + o.clock + " --seed " +
                      std::to_string(seed) + " --log '" + f.record.log + "' --json '" + json + "' --no-progress";
    for (const auto& ov : overrides) cmd += " --set '" + ov.key_path + "=" + ov.value + "'";
    cmd += " > '" + (fs::path(o.work_dir) / fmt::format("{}_seed{}.out", name, seed)).string() + "' 2>&1";
    std::system(cmd.c_str());
    if (!fs::exists(json)) throw std::runtime_error("flight " + name + ": rig run wrote no report (" + cmd + ")");
    const YAML::Node j = load_yaml_file(json, "", InputKind::kCampaign);
    f.record.result = j["result"].as<std::string>();
    f.record.controlled = j["controlled"].as<bool>();
    f.record.sim_s = j["sim_time_s"].as<double>();
    f.range_p = j["ranges"]["p"].as<double>();
    f.range_v = j["ranges"]["v"].as<double>();
    f.range_phi = j["ranges"]["phi"].as<double>();
    if (o.states == "smoothed") f.smoothing = smoothing_of(load_scenario(scenario, overrides));
  }
  f.record.wall_s = seconds_since(t0);
  if (o.progress) {
    std::cerr << fmt::format("rig reproduce: flew {} seed {} ({}) in {:.2f} s: {}\n", name, seed,
                             fs::path(scenario).filename().string(), f.record.wall_s, f.record.result);
  }
  return f;
}

std::vector<std::complex<double>> model_eigenvalues(const DerivativeModel& model, const Vehicle& vehicle) {
  const Eigen::VectorXcd eig = build_state_space(model, vehicle).A.eigenvalues();
  return {eig.data(), eig.data() + eig.size()};
}

/// Table 9.6's non-dimensional derivatives (thesis Eq 9.2 with Eq 9.3: f 17 Hz as the thesis, the
/// vehicle's wing data) of dimensional derivatives `d`.
void put_nondimensional(CellMap& m, const std::string& row, const std::function<double(const char*)>& d,
                        const Vehicle& v) {
  const double f = v.flap_frequency_hz, rho = v.air_density_kgpm3, A = v.wing_area_m2, c = v.mean_chord_m;
  const double U = 2.0 * v.flap_amplitude_rad * f * v.r2_m;
  m[row + " / Lp+"] = d("Lp") * f / (rho * U * U * A * c);
  m[row + " / Lv+"] = d("Lv") / (rho * U * A * c);
  m[row + " / Yp+"] = d("Yp") * f / (rho * U * U * A);
  m[row + " / Yv+"] = d("Yv") / (rho * U * A);
}

/// Table 8.8: the eigenvalues of the four-state model file.
CellMap table_8_8(const CampaignSpec& spec) {
  const DerivativeModel lat4 = load_model(spec.lateral4_model);
  CellMap m;
  put_eigenvalues4(m, "lateral4", model_eigenvalues(lat4, load_vehicle(lat4.vehicle_file)));
  return m;
}

std::string overrides_key(const std::map<std::string, std::string>& with) {
  std::string k;
  for (const auto& [key, value] : with) k += key + "=" + value + ";";
  return k;
}

/// A flight of the campaign: `flight` flown on `seed` with `with`; flown once per key.
std::string flight_key(std::uint64_t seed, const std::string& flight, const std::map<std::string, std::string>& with) {
  return fmt::format("{}|{}|{}", seed, flight, overrides_key(with));
}

/// A table's values on its flight flown with a cause, over the seeds, and the flights with the
/// cause that did not fly as their scenario asks.
struct WithCause {
  std::vector<CellMap> seeds;
  std::vector<std::string> failures;
};

/// One run of the campaign: the flights of every seed, the values of every table.
class CampaignRun {
 public:
  CampaignRun(const CampaignOptions& o, const CampaignSpec& spec, CampaignResult& result)
      : o_(o), spec_(spec), result_(result), controller_(load_controller_config(o.controller_file)) {}

  void fly_seed(std::uint64_t seed, bool plots) {
    seed_ = seed;
    plots_ = plots;
    identification_sets();
    for (const std::string id : {"7", "8", "15", "16", "9", "10", "11", "12", "13", "14"}) {
      values_[id].push_back(table_on(id, base_flight(id)));
    }
    structure_flights();
  }

  /// Table `id`'s flight flown on `seed` with a cause (`with`), labelled `label` if it is not
  /// flown yet: its values, the flight named in `failure` if it did not fly as its scenario asks,
  /// and its record if this call flew it.
  WithFlight fly_item(std::uint64_t seed, const std::string& id, const std::map<std::string, std::string>& with,
                      const std::string& label) {
    seed_ = seed;
    plots_ = false;
    const std::size_t flown_before = result_.flights.size();
    const Flown& f = flight_with(table_flight(id), with, label);
    WithFlight out;
    out.cells = table_on(id, f);
    if (f.record.result != "ok") out.failure = fmt::format("{} seed {}: {}", f.record.name, seed, f.record.result);
    if (result_.flights.size() > flown_before) out.record = result_.flights.back();
    return out;
  }

  /// What this run flew on its one seed (fly_seed()): every table's values, the identified and
  /// the plant's derivatives, the flights' records.
  SeedValues seed_values() const {
    SeedValues v;
    v.seed = seed_;
    for (const auto& [id, seeds] : values_) v.tables[id] = seeds.back();
    for (const auto& [row, derivatives] : identified_) {
      for (const auto& [d, values] : derivatives) v.identified[row][d] = values.back();
    }
    v.plant = plant_;
    v.flights = result_.flights;
    return v;
  }

 private:
  ident::RigLogData read(const Flown& f) const {
    ident::LogReadOptions ro;
    ro.smoothing = f.smoothing;
    return ident::read_rig_log(f.record.log, ident::state_source_from_name(o_.states), ro);
  }

  std::vector<Override> set_overrides(const CampaignSpec::Set& set) const {
    std::vector<Override> ov{{"model", set.model}};
    if (!set.manoeuvre.empty()) ov.push_back({"manoeuvre", set.manoeuvre});
    return ov;
  }

  /// The identification flight of every set: Tables 9.4, 9.5 (and 9.6, 4 from set 1).
  void identification_sets() {
    CellMap t94, t95, t96, t4, t95_oe, t96_oe;
    std::vector<std::pair<std::string, std::vector<std::complex<double>>>> all_eigenvalues;
    for (const auto& set : spec_.sets) {
      const bool first = set.row == spec_.sets.front().row;
      const std::string name = first ? "identification" : "identification_" + set.row.substr(set.row.rfind(' ') + 1);
      const Flown f = fly(o_, seed_, name, spec_.flights.at("identification"), set_overrides(set));
      result_.flights.push_back(f.record);
      t94[set.row + " / p"] = f.range_p;
      t94[set.row + " / v"] = f.range_v;
      t94[set.row + " / phi"] = f.range_phi;
      const DerivativeModel truth = load_model(set.model);
      const Vehicle vehicle = load_vehicle(truth.vehicle_file);
      const ident::FlightData measured = read(f).measured;
      ident::IdentResult id = identify_as_thesis(measured, vehicle, truth.vehicle_file, "rig_" + set.row);
      ident::IdentOptions by_output_error;
      by_output_error.method = ident::Method::kOutputError;
      const ident::IdentResult oe =
          identify_as_thesis(measured, vehicle, truth.vehicle_file, "rig_" + set.row, by_output_error);
      put_eigenvalues(t95, set.row, id.eigenvalues);
      put_eigenvalues(t95_oe, set.row, oe.eigenvalues);
      for (const char* d : kCheckedDerivatives) {
        const std::string ee = d, oe_key = std::string(d) + kOutputErrorSuffix;
        identified_[set.row][ee].push_back(id.parameters.at(d).value);
        identified_[set.row][oe_key].push_back(oe.parameters.at(d).value);
        identified_[set.row][ee + kOwnSigmaSuffix].push_back(id.parameters.at(d).sigma_coloured);
        identified_[set.row][oe_key + kOwnSigmaSuffix].push_back(oe.parameters.at(d).sigma_coloured);
        plant_[set.row][d] = truth.derivatives.at(d);
      }
      all_eigenvalues.emplace_back(set.row, id.eigenvalues);
      if (first) {
        put_nondimensional(
            t96, set.row, [&id](const char* n) { return id.parameters.at(n).value; }, id.vehicle);
        put_nondimensional(
            t96_oe, set.row, [&oe](const char* n) { return oe.parameters.at(n).value; }, oe.vehicle);
        put_fit(t4, "p_dot", fit_of(id.fits, "p_dot").metrics);
        put_fit(t4, "v_dot", fit_of(id.fits, "v_dot_star").metrics);
        if (plots_ && !o_.report_dir.empty()) {
          const fs::path dir = fs::path(o_.report_dir) / "identification_set_1";
          fs::create_directories(dir);
          ident::plot_identification(id, dir.string());
        }
        for (auto& [table, cells] : three_state_tables(measured, id)) values_[table].push_back(std::move(cells));
        set1_[seed_] = std::move(id);
        set1_flight_[seed_] = f;
      }
    }
    values_["9.4"].push_back(t94);
    values_["9.5"].push_back(t95);
    values_["9.6"].push_back(t96);
    values_["9.5-oe"].push_back(t95_oe);
    values_["9.6-oe"].push_back(t96_oe);
    values_["4"].push_back(t4);
    if (plots_ && !o_.report_dir.empty()) plot_eigenvalue_map(o_.report_dir, all_eigenvalues, spec_.tables.at("9.5"));
  }

  /// The flights of the model-structure tables (reproduce/structure_tables.h): the four-state
  /// flight, and the identification train on each of Appendix E's input variants. A flight that
  /// did not fly as its scenario asks (a failsafe) gives its tables no values on this seed: it is
  /// listed among the flights not ok, and its cells have no value to judge.
  void structure_flights() {
    const Flown& four = flight_with("lateral4", {});
    std::map<std::string, CellMap> cells;
    if (four.record.result == "ok") cells = four_state_tables(read(four).measured, load_model(spec_.lateral4_model));
    for (const std::string& table : four_state_table_ids()) values_[table].push_back(std::move(cells[table]));
    for (const auto& [table, model] : spec_.input_variants) {
      const std::string name = "identification_" + table;
      const Flown f = fly(o_, seed_, name, spec_.flights.at("identification"), {{"model", model}});
      result_.flights.push_back(f.record);
      values_[table].push_back(f.record.result == "ok" ? input_variant_table(read(f).measured, load_model(model))
                                                       : CellMap{});
    }
  }

  const Flown& base_flight(const std::string& id) {
    const std::string flight = table_flight(id);
    if (flight == "identification") return set1_flight_.at(seed_);
    return flight_with(flight, {});
  }

  /// The flight `name` on this seed with `with`, flown once; a flight with a cause is labelled
  /// `label` (the campaign's plan numbers them, plan_items()).
  const Flown& flight_with(const std::string& name, const std::map<std::string, std::string>& with,
                           const std::string& label = "") {
    const std::string key = flight_key(seed_, name, with);
    auto it = flown_.find(key);
    if (it != flown_.end()) return it->second;
    std::vector<Override> ov;
    if (name == "identification") ov = set_overrides(spec_.sets.front());
    for (const auto& [k, v] : with) ov.push_back({k, v});
    Flown f = fly(o_, seed_, with.empty() ? name : label, spec_.flights.at(name), ov);
    result_.flights.push_back(f.record);
    return flown_.emplace(key, std::move(f)).first->second;
  }

  /// Table `id`'s values on flight `f` (validation tables).
  CellMap table_on(const std::string& id, const Flown& f) {
    CellMap m;
    const DerivativeModel& model = set1_.at(seed_).model;
    const Vehicle& vehicle = set1_.at(seed_).vehicle;
    const ident::RigLogData data = read(f);
    const bool plot = plots_ && !o_.report_dir.empty();
    const fs::path dir = fs::path(o_.report_dir) / ("table_" + id + "_" + f.record.name);
    if (id == "9" || id == "10" || id == "11") {
      ident::ClosedLoopOptions cl;
      cl.controller = controller_;
      cl.gain_set = data.gain_set.empty() ? "fast" : data.gain_set;
      const ident::ClosedLoopResult r = ident::validate_closed_loop(data.measured, model, vehicle, cl);
      for (const char* s : {"p", "v", "phi", "delta_f"}) put_fit(m, s, r.fits.at(s));
      if (plot) {
        fs::create_directories(dir);
        ident::plot_closed_loop(r, dir.string());
      }
      return m;
    }
    const auto other = spec_.coupled_models.find(id);
    const DerivativeModel m_other = other != spec_.coupled_models.end() ? load_model(other->second) : model;
    const Vehicle v_other = other != spec_.coupled_models.end() ? load_vehicle(m_other.vehicle_file) : vehicle;
    const ident::ValidationResult v =
        ident::validate_open_loop(data.measured, m_other, v_other, ident::ValidationOptions{});
    for (const char* out : {"p_dot", "v_dot", "phi_dot"}) put_fit(m, out, fit_of(v.fits, out).metrics);
    if (plot && other == spec_.coupled_models.end()) {
      fs::create_directories(dir);
      ident::plot_validation(v, dir.string());
    }
    return m;
  }

  const CampaignOptions& o_;
  const CampaignSpec& spec_;
  CampaignResult& result_;
  ControllerConfig controller_;
  std::uint64_t seed_ = 1;
  bool plots_ = false;
  std::map<std::uint64_t, ident::IdentResult> set1_;  ///< set 1's identified model, by seed
  std::map<std::uint64_t, Flown> set1_flight_;        ///< set 1's identification flight, by seed
  std::map<std::string, Flown> flown_;
  std::map<std::string, std::vector<CellMap>> values_;
  std::map<std::string, std::map<std::string, std::vector<double>>> identified_;  ///< row -> derivative -> seeds
  std::map<std::string, std::map<std::string, double>> plant_;                    ///< row -> derivative
};

/// The values of `cell` over the seeds (NaN where a seed has none).
std::vector<double> over_seeds(const std::vector<CellMap>& seeds, const std::string& cell) {
  std::vector<double> x;
  for (const CellMap& m : seeds) {
    const auto it = m.find(cell);
    x.push_back(it == m.end() ? NAN : it->second);
  }
  return x;
}

/// Marks cells whose published value and rig values repeat an earlier cell's (counted once).
void mark_repeats(std::vector<Table>& tables,
                  const std::map<std::string, std::map<std::string, std::vector<double>>>& raw) {
  std::vector<std::pair<std::string, std::vector<double>>> seen;  // "table / row / column", published + values
  for (Table& t : tables) {
    for (Cell& c : t.cells) {
      std::vector<double> sig{c.published};
      const auto& v = raw.at(t.id).at(c.row + " / " + c.column);
      sig.insert(sig.end(), v.begin(), v.end());
      for (const auto& [name, s] : seen) {
        if (s == sig) {
          c.repeats = name;
          break;
        }
      }
      if (c.repeats.empty()) seen.emplace_back(t.id + " / " + c.row + " / " + c.column, sig);
    }
  }
}

/// The closed-loop tables every closed-loop cause is flown on.
const std::array<const char*, 3> kClosedLoopTables = {"9", "10", "11"};

/// The flights with a cause, in the order the campaign flies them on each seed: the reasons'
/// causes (each table and cause once), then every closed-loop cause on Tables 9-11.
struct PlanItem {
  std::string table;
  std::map<std::string, std::string> with;
};

std::vector<PlanItem> plan_items(const CampaignSpec& spec) {
  std::vector<PlanItem> items;
  std::set<std::string> seen;
  for (const std::string& id : campaign_table_ids()) {
    for (const Reason& r : spec.tables.at(id).reasons) {
      if (!r.with.empty() && seen.insert(id + "|" + overrides_key(r.with)).second) items.push_back({id, r.with});
    }
  }
  for (const CauseSpec& cause : spec.causes) {
    for (const std::string id : kClosedLoopTables) items.push_back({id, cause.with});
  }
  return items;
}

/// Each item's flight's label, the same on every seed: "<flight>_with_<k>", k counting the flights with a
/// cause item by item (so a seed kept in a campaign directory reads back
/// with the labels any seed list gives it); a flight two items share (the same flight and cause)
/// is flown once per seed, under the first item's label.
std::vector<std::string> plan_labels(const std::vector<PlanItem>& items) {
  std::vector<std::string> labels(items.size());
  std::map<std::string, std::string> label_of;  // flight and cause -> label
  int k = 0;
  for (std::size_t j = 0; j < items.size(); ++j) {
    const std::string flight = table_flight(items[j].table);
    const std::string key = flight + "|" + overrides_key(items[j].with);
    auto it = label_of.find(key);
    if (it == label_of.end()) it = label_of.emplace(key, fmt::format("{}_with_{}", flight, ++k)).first;
    labels[j] = it->second;
  }
  return labels;
}

/// Every seed flown in the campaigns' worker pool (`jobs` at a time), each with all its flights
/// (its own and those with a cause), and read back in the seeds' order; with `files`, a seed kept
/// there is read, not flown, and each one flown is kept.
std::vector<SeedValues> fly_seeds(const CampaignOptions& o, const CampaignSpec& spec,
                                  const std::vector<PlanItem>& items, const campaign::ResultFiles* files) {
  const std::vector<std::string> labels = plan_labels(items);
  campaign::PoolWork pool;
  pool.work = [&](std::size_t i) {
    CampaignResult flown;
    CampaignRun run(o, spec, flown);
    run.fly_seed(o.seeds[i], i == 0);
    SeedValues v = run.seed_values();
    for (std::size_t j = 0; j < items.size(); ++j) {
      v.with.push_back(run.fly_item(o.seeds[i], items[j].table, items[j].with, labels[j]));
    }
    return seed_values_line(v);
  };
  pool.died = [](std::size_t, const std::string& how) { return "error the worker flying it died (" + how + ")"; };
  campaign::KeptItems kept;
  for (const std::uint64_t seed : o.seeds) kept.keys.push_back(seed_key(seed));
  kept.keep = [](const std::string& line) { return line.rfind("error ", 0) != 0; };
  // Only a flight flown now draws the figures: the first seed flies again for --report.
  kept.redo = [&o](std::size_t i) { return i == 0 && !o.report_dir.empty(); };
  const std::vector<std::string> lines = campaign::run_kept(kept, std::max(1, o.jobs), pool, files);
  std::vector<SeedValues> seeds;
  for (std::size_t i = 0; i < lines.size(); ++i) {
    if (lines[i].rfind("error ", 0) == 0) {
      throw std::runtime_error(fmt::format("rig reproduce: seed {}: {}", o.seeds[i], lines[i].substr(6)));
    }
    seeds.push_back(seed_values_from_line(lines[i]));
  }
  return seeds;
}

}  // namespace

CampaignResult run_campaign(const CampaignOptions& o) {
  const auto t0 = Clock::now();
  if (o.seeds.empty()) throw ConfigError(o.campaign_file, "seeds", "", "at least one seed");
  const CampaignSpec spec = load_campaign(o.campaign_file);
  // The campaign directory, taken before anything is written (one writer) and held to the end.
  std::optional<campaign::ResultFiles> files;
  if (!o.result_dir.empty()) files = campaign::open_result_dir(o.result_dir, seeds_manifest(o, spec));
  fs::create_directories(o.work_dir);
  if (!o.report_dir.empty()) {
    plots::require_gnuplot();
    fs::create_directories(o.report_dir);
  }
  CampaignResult result;
  result.states = o.states;
  result.campaign = o.campaign_file;
  result.clock = o.clock;
  result.overrides = override_texts(o.overrides);
  result.seeds = o.seeds;

  const std::vector<PlanItem> items = plan_items(spec);
  const std::vector<SeedValues> seeds = fly_seeds(o, spec, items, files ? &*files : nullptr);
  std::map<std::string, std::vector<CellMap>> values;
  for (const SeedValues& v : seeds) {
    result.flights.insert(result.flights.end(), v.flights.begin(), v.flights.end());
    for (const auto& [id, cells] : v.tables) values[id].push_back(cells);
  }
  result.plant_check = plant_check(spec, seeds);
  // The tables that are arithmetic on the model files: the same on every seed.
  {
    CellMap eig, nd;
    for (const auto& set : spec.sets) {
      const DerivativeModel m = load_model(set.model);
      const Vehicle v = load_vehicle(m.vehicle_file);
      put_eigenvalues(eig, set.row, model_eigenvalues(m, v));
      if (set.row == spec.sets.front().row) {
        put_nondimensional(
            nd, set.row, [&m](const char* n) { return m.derivatives.at(n); }, v);
      }
    }
    values["9.5-model"] = {eig};
    values["9.6-model"] = {nd};
    values["8.8"] = {table_8_8(spec)};
    for (auto& [id, cells] : structure_model_tables(spec)) values[id] = {std::move(cells)};
  }
  // The flights with each cause, over the seeds, item by item.
  std::vector<WithCause> flown(items.size());
  for (std::size_t j = 0; j < items.size(); ++j) {
    for (const SeedValues& v : seeds) {
      flown[j].seeds.push_back(v.with[j].cells);
      if (!v.with[j].failure.empty()) flown[j].failures.push_back(v.with[j].failure);
      if (v.with[j].record) result.flights.push_back(*v.with[j].record);
    }
  }
  std::map<std::string, std::map<std::string, WithCause>> with;  // table -> overrides -> flights
  std::size_t j = 0;
  for (; j < items.size() - kClosedLoopTables.size() * spec.causes.size(); ++j) {
    with[items[j].table][overrides_key(items[j].with)] = flown[j];
  }
  for (const CauseSpec& cause : spec.causes) {
    CauseStudy study;
    study.name = cause.name;
    study.source = cause.source;
    for (const auto& [k, v] : cause.with) study.overrides.push_back(k + "=" + v);
    for (const std::string id : kClosedLoopTables) {
      const WithCause& cause_flown = flown[j++];
      study.failures.insert(study.failures.end(), cause_flown.failures.begin(), cause_flown.failures.end());
      const TableSpec& t = spec.tables.at(id);
      for (const auto& row : t.row_order) {
        CauseCell c;
        c.table = id;
        c.row = row;
        c.column = "R2";
        if (t.published.at(row).count("R2") == 0) continue;
        c.published = t.published.at(row).at("R2");
        double sd = 0, hw = 0;
        mean_interval(over_seeds(values.at(id), row + " / R2"), &c.rig, &sd, &hw);
        mean_interval(over_seeds(cause_flown.seeds, row + " / R2"), &c.with_cause, &sd, &c.interval);
        study.cells.push_back(c);
      }
    }
    result.causes.push_back(study);
  }

  // Judge every cell.
  std::map<std::string, std::map<std::string, std::vector<double>>> raw;
  for (const std::string& id : campaign_table_ids()) {
    const TableSpec& spec_t = spec.tables.at(id);
    Table table;
    table.id = id;
    table.title = spec_t.title;
    table.category = category_name(spec_t.category);
    table.why = spec_t.why;
    table.against_plant = !spec_t.reference_table.empty();
    for (const auto& row : spec_t.row_order) {
      for (const auto& column : spec_t.column_order.at(row)) {
        const std::string key = row + " / " + column;
        JudgeContext ctx;
        ctx.states = o.states;
        if (const Reason* r = spec_t.reason_for(key); r != nullptr && !r->with.empty()) {
          const WithCause& flown = with[id][overrides_key(r->with)];
          ctx.with_values = over_seeds(flown.seeds, key);
          if (!flown.failures.empty()) ctx.with_failure = flown.failures.front();
        }
        if (!spec_t.reference_table.empty()) ctx.reference = over_seeds(values.at(spec_t.reference_table), key).front();
        const std::vector<double> x = over_seeds(values.at(id), key);
        raw[id][key] = x;
        table.cells.push_back(judge(spec_t, row, column, x, ctx));
      }
    }
    result.tables.push_back(table);
  }
  mark_repeats(result.tables, raw);
  result.wall_s = seconds_since(t0);
  return result;
}

}  // namespace nimble::reproduce
