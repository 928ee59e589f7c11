/// Reading and checking the campaign file of `rig reproduce thesis` (reproduce/campaign_spec.h).

#include "reproduce/campaign_spec.h"

#include <cmath>
#include <filesystem>
#include <set>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "core/config.h"

namespace nimble::reproduce {
namespace {

namespace fs = std::filesystem;

std::string resolve(const std::string& file, const std::string& path) {
  return (fs::path(path).is_absolute() ? fs::path(path) : fs::path(file).parent_path() / path)
      .lexically_normal()
      .string();
}

/// A mapping of scalars as strings (scenario overrides).
std::map<std::string, std::string> string_map(ConfigMap& parent, const std::string& key) {
  const YAML::Node node = parent.get_node(key);
  if (!node.IsMap() || node.size() == 0) parent.fail(key, "must map scenario keys to values");
  std::map<std::string, std::string> out;
  for (const auto& item : node) {
    if (!item.second.IsScalar()) parent.fail(key, "the value of " + item.first.as<std::string>() + " must be a scalar");
    out[item.first.as<std::string>()] = item.second.as<std::string>();
  }
  return out;
}

/// A mapping of numbers in `range` (keys kept as written).
std::map<std::string, double> double_map(ConfigMap& parent, const std::string& key, const Range& range) {
  const YAML::Node node = parent.get_node(key);
  ConfigMap m = parent.get_map(key);
  std::map<std::string, double> out;
  for (const auto& item : node) {
    const std::string k = item.first.as<std::string>();
    out[k] = m.get_double(k, range);
  }
  m.finish();
  return out;
}

/// Half a unit of the last digit of a number as written ("0.900": 0.0005; "12": 0.5; "6.00e-2":
/// 0.00005, the mantissa's last digit at the exponent).
double printed_half_digit(const std::string& text) {
  const auto e = text.find_first_of("eE");
  const std::string mantissa = text.substr(0, e);
  const auto dot = mantissa.find('.');
  const double decimals = dot == std::string::npos ? 0.0 : static_cast<double>(mantissa.size() - dot - 1);
  const double exponent = e == std::string::npos ? 0.0 : std::stod(text.substr(e + 1));
  return 0.5 * std::pow(10.0, exponent - decimals);
}

/// Fails on `key` unless `cell` ("row / column") is a published cell of `t`.
void require_cell(const ConfigMap& m, const std::string& key, const TableSpec& t, const std::string& cell) {
  const auto slash = cell.find(" / ");
  const auto pr = slash == std::string::npos ? t.published.end() : t.published.find(cell.substr(0, slash));
  if (pr == t.published.end() || pr->second.count(cell.substr(slash + 3)) == 0) {
    m.fail(key, "'" + cell + "' is not a published cell of this table (\"row / column\")");
  }
}

Reason load_reason(const YAML::Node& node, const std::string& file, const std::string& path, const TableSpec& t,
                   const std::string& id) {
  ConfigMap r(node, file, path);
  Reason out;
  out.cells = r.get_string_list("cells");
  if (out.cells.empty()) r.fail("cells", "must name at least one cell");
  for (const std::string& cell : out.cells) {
    if (cell.find('*') != std::string::npos) {
      r.fail("cells", "'" + cell + "': no wildcards; a reason names each cell it explains (\"row / column\")");
    }
    require_cell(r, "cells", t, cell);
    if (t.reason_for(cell) != nullptr) r.fail("cells", "'" + cell + "' already has a reason");
  }
  out.text = r.get_string("text");
  // Every reason says where the rig's value lies, how far off it may be, and for which states
  // it holds: the run checks all three (reproduce/cell_verdict.h).
  out.rig = r.get_enum("rig", {"above", "below"});
  out.max_off = r.get_double("max_off", Range::closed(0.0, 1e9));
  out.states = r.get_string_list("states");
  if (out.states.empty()) r.fail("states", "must name the state sources the reason holds for");
  for (const auto& s : out.states) {
    if (s != "smoothed" && s != "estimate" && s != "truth")
      r.fail("states", "'" + s + "': smoothed, estimate or truth");
  }
  if (r.has("with")) {
    if (table_flight(id).empty()) r.fail("with", "table " + id + " has no flight of its own to fly with a cause");
    out.with = string_map(r, "with");
    if (r.has("moves")) out.moves = r.get_enum("moves", {"toward", "away"});
    if (r.has("at_least")) out.at_least = r.get_double("at_least", Range::closed(0.0, 1.0));
  }
  r.finish();
  return out;
}

/// One table of the campaign file (`t`, table `id`).
TableSpec load_table(ConfigMap& t, const std::string& file, const std::string& id) {
  TableSpec s;
  s.title = t.get_string("title");
  // The category follows from what the cells are computed from, in code: never from this file.
  const Source source = table_source(id);
  for (const char* key : {"category", "why"}) {
    if (t.has(key)) {
      t.fail(key, fmt::format("the code decides a table's category from what its cells are computed from "
                              "(reproduce/campaign_spec.h): table {}'s are {}",
                              id, source_statement(source)));
    }
  }
  s.category = category_of(source);
  s.why = source_statement(source);
  s.reference_table = reference_table(id);
  if (!s.reference_table.empty()) {
    for (const char* key : {"tolerance", "thesis_sigma", "calibrated", "reasons"}) {
      if (t.has(key)) {
        t.fail(key, "table " + id +
                        " is a pipeline check, judged against the plant file within half the published "
                        "number's last digit (reproduce/cell_verdict.h): it takes no " +
                        key);
      }
    }
  } else {
    ConfigMap tol = t.get_map("tolerance");
    s.relative = tol.get_double_or("relative", 0.0, Range::closed(0.0, 10.0));
    s.thesis_sigmas = tol.get_double_or("thesis_sigmas", 0.0, Range::closed(0.0, 10.0));
    s.min_seeds = static_cast<int>(tol.get_double_or("min_seeds", 1.0, Range::closed(1.0, 1000.0)));
    if (tol.has("absolute")) s.absolute = double_map(tol, "absolute", Range::closed(0.0, 1e6));
    tol.finish();
  }
  const YAML::Node published = t.get_node("published");
  if (!published.IsMap() || published.size() == 0) t.fail("published", "must map rows to their published columns");
  for (const auto& row : published) {
    const std::string name = row.first.as<std::string>();
    s.row_order.push_back(name);
    ConfigMap cols(row.second, file, t.key_path("published") + "." + name);
    for (const auto& col : row.second) {
      const std::string cname = col.first.as<std::string>();
      s.published[name][cname] = cols.get_double(cname);
      s.printed_half_digit[name][cname] = printed_half_digit(col.second.Scalar());
      s.column_order[name].push_back(cname);
    }
    cols.finish();
  }
  if (t.has("thesis_sigma")) {
    s.thesis_sigma = double_map(t, "thesis_sigma", Range::closed(0.0, 1e9));
    for (const auto& [cell, sigma] : s.thesis_sigma) require_cell(t, "thesis_sigma", s, cell);
  }
  if (t.has("calibrated")) {
    if (s.category != Category::kFlights) t.fail("calibrated", "names the tuned cells of a flights table");
    ConfigMap cal = t.get_map("calibrated");
    s.calibrated_cells = cal.get_string_list("cells");
    s.calibrated_why = cal.get_string("why");
    cal.finish();
    for (const std::string& cell : s.calibrated_cells) require_cell(t, "calibrated", s, cell);
  }
  if (t.has("reasons")) {
    if (s.category != Category::kFlights) {
      t.fail("reasons", "only a table of the rig's own flights (category flights) has reasons");
    }
    const YAML::Node rs = t.get_node("reasons");
    if (!rs.IsSequence()) t.fail("reasons", "must be a list of {cells, text, and a predicate}");
    for (std::size_t i = 0; i < rs.size(); ++i) {
      s.reasons.push_back(load_reason(rs[i], file, t.key_path("reasons") + "[" + std::to_string(i) + "]", s, id));
    }
  }
  if (t.has("explained")) t.fail("explained", "replaced by reasons: each names its cells and a checked predicate");
  t.finish();
  return s;
}

}  // namespace

const std::vector<std::string>& campaign_table_ids() {
  static const std::vector<std::string> ids = {
      "9.4", "9.5", "9.5-oe", "9.5-model", "9.6", "9.6-oe", "9.6-model", "8.8", "4", "7", "8", "9", "10", "11", "12",
      "13", "14", "15", "16",
      // The thesis's model structures (chapter 8, Appendices D, E, H: reproduce/structure_tables.h).
      "8.2", "8.4", "8.7", "8.9-model", "8.9", "8.10", "8.11", "8.13-model", "8.13", "8.14", "8.15", "D.1", "D.2",
      "E.2-model", "E.2", "E.3-model", "E.3", "H.1", "H.2", "H.3", "H.4", "H.5"};
  return ids;
}

Source table_source(const std::string& id) {
  if (id == "9.4") return Source::kFlightRanges;
  if (!reference_table(id).empty()) return Source::kReidentifiedPlant;
  static const std::set<std::string> arithmetic = {"9.5-model",  "9.6-model", "8.8",      "8.9-model",
                                                   "8.13-model", "E.2-model", "E.3-model"};
  if (arithmetic.count(id) > 0) return Source::kModelArithmetic;
  if (id.rfind("H.", 0) == 0) return Source::kFlightCorrelation;
  return Source::kFlightFit;
}

Category category_of(Source s) {
  return s == Source::kFlightRanges || s == Source::kFlightFit || s == Source::kFlightCorrelation ? Category::kFlights
                                                                                                  : Category::kModel;
}

const char* source_statement(Source s) {
  switch (s) {
    case Source::kFlightRanges:
      return "ranges of the rig's own flights: what its excitation, controller and sensing make of the plant";
    case Source::kReidentifiedPlant:
      return "the rig's identification of its own plant file from its flights: a check of the pipeline (states, "
             "identification) against the plant file's exact value, the thesis's number beside it";
    case Source::kModelArithmetic:
      return "arithmetic on a transcribed model file: a check of the transcription against the thesis";
    case Source::kFlightCorrelation:
      return "parameter correlations of the rig's identification of its own flight: what its excitation, controller "
             "and sensing leave separable (the plant file does not fix them); the thesis prints |rho|";
    case Source::kFlightFit:
      return "fit metrics of a model on the rig's flights, which carry the rig's sensing noise, estimator and "
             "effects (the plant file does not fix them): a difference says what the rig's flights lack or add";
  }
  return "?";
}

std::string reference_table(const std::string& id) {
  // A re-identification of the plant, by either method, against the arithmetic on its model file.
  // The model structures' tables (reproduce/structure_tables.h): the black-box models against the
  // grey-box plant file they were fitted to fly; D.1 and D.2 (OLS and WLS rows) against tables of
  // the plant file's derivatives that are not printed (kPlantDerivatives*).
  static const std::map<std::string, std::string> reference = {
      {"9.5", "9.5-model"},         {"9.5-oe", "9.5-model"},     {"9.6", "9.6-model"},
      {"9.6-oe", "9.6-model"},      {"8.9", "8.9-model"},        {"8.10", "8.8"},
      {"8.11", "8.9-model"},        {"8.13", "8.13-model"},      {"8.14", "9.5-model"},
      {"8.15", "8.13-model"},       {"E.2", "E.2-model"},        {"E.3", "E.3-model"},
      {"D.1", kPlantDerivativesD1}, {"D.2", kPlantDerivativesD2}};
  const auto it = reference.find(id);
  return it == reference.end() ? "" : it->second;
}

std::string table_flight(const std::string& id) {
  static const std::map<std::string, std::string> flights = {
      {"7", "ol_doublet"},        {"8", "ol_112"},        {"12", "coupled"},      {"13", "coupled"},
      {"14", "coupled"},          {"15", "nonlinear_30"}, {"16", "nonlinear_20"}, {"9", "identification"},
      {"10", "cl_doublet_train"}, {"11", "cl_112"}};
  const auto it = flights.find(id);
  return it == flights.end() ? "" : it->second;
}

CampaignSpec load_campaign(const std::string& file) {
  CampaignSpec c;
  c.file = file;
  ConfigMap root = ConfigMap::load_file(file);
  root.get_string("name");
  {
    ConfigMap flights = root.get_map("flights");
    for (const char* name : {"identification", "ol_doublet", "ol_112", "cl_doublet_train", "cl_112", "coupled",
                             "nonlinear_20", "nonlinear_30", "lateral4"}) {
      c.flights[name] = resolve(file, flights.get_string(name));
    }
    flights.finish();
  }
  {
    const YAML::Node sets = root.get_node("sets");
    if (!sets.IsMap() || sets.size() == 0) root.fail("sets", "must map each set's row name to its model and manoeuvre");
    for (const auto& item : sets) {
      const std::string row = item.first.as<std::string>();
      ConfigMap set(item.second, file, root.key_path("sets") + "." + row);
      c.sets.push_back({row, resolve(file, set.get_string("model")),
                        set.has("manoeuvre") ? resolve(file, set.get_string("manoeuvre")) : ""});
      set.finish();
    }
  }
  c.lateral4_model = resolve(file, root.get_string("lateral4_model"));
  // The sizes reasons' checks fly: read through the YAML anchors of the reasons that use them.
  if (root.has("sizes")) root.get_node("sizes");
  {
    ConfigMap cm = root.get_map("coupled_models");
    for (const char* id : {"13", "14"}) c.coupled_models[id] = resolve(file, cm.get_string(id));
    cm.finish();
  }
  {
    ConfigMap iv = root.get_map("input_variants");
    for (const char* id : {"E.2", "E.3"}) c.input_variants[id] = resolve(file, iv.get_string(id));
    iv.finish();
  }
  if (root.has("closed_loop_causes")) {
    const YAML::Node causes = root.get_node("closed_loop_causes");
    if (!causes.IsSequence()) root.fail("closed_loop_causes", "must be a list of {name, source, with}");
    for (std::size_t i = 0; i < causes.size(); ++i) {
      ConfigMap m(causes[i], file, root.key_path("closed_loop_causes") + "[" + std::to_string(i) + "]");
      CauseSpec cause;
      cause.name = m.get_string("name");
      cause.source = m.get_string("source");
      cause.with = string_map(m, "with");
      m.finish();
      c.causes.push_back(cause);
    }
  }
  ConfigMap tables = root.get_map("tables");
  for (const std::string& id : campaign_table_ids()) {
    ConfigMap t = tables.get_map(id);
    c.tables[id] = load_table(t, file, id);
  }
  tables.finish();
  root.finish();
  return c;
}

}  // namespace nimble::reproduce
