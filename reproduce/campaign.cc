#include "reproduce/campaign.h"

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <complex>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>
#include <yaml-cpp/yaml.h>

#include "controller/attitude_controller.h"
#include "core/config.h"
#include "core/json_writer.h"
#include "core/model.h"
#include "core/output_file.h"
#include "core/vehicle.h"
#include "ident/closed_loop.h"
#include "ident/identify.h"
#include "ident/plots.h"
#include "ident/rig_log.h"
#include "ident/validate.h"
#include "launcher/inprocess.h"
#include "launcher/run_plan.h"

namespace nimble::reproduce {
namespace {

namespace fs = std::filesystem;
using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }

/// What a table's `match` is: a relative tolerance, absolute tolerances per column, or a
/// tolerance relative to the modulus of the eigenvalue the cell belongs to.
struct Tolerance {
  double relative = 0.0;
  double relative_to_modulus = 0.0;
  /// Also a match within this many standard deviations of the rig's estimate (its Newey-West
  /// sigma, coloured residuals), where that is wider: for identified parameters.
  double sigmas = 0.0;
  std::map<std::string, double> absolute;  ///< by column
};

struct TableSpec {
  std::string title;
  Tolerance tolerance;
  std::map<std::string, std::map<std::string, double>> published;  ///< row -> column -> value
  std::map<std::string, std::string> explained;                     ///< "row / column" or "*" -> reason
  std::vector<std::string> row_order;
};

struct CampaignSpec {
  std::string file;
  std::map<std::string, std::string> flights;  ///< name -> scenario
  struct Set {
    std::string row;        ///< "set N"
    std::string model;      ///< the set's model file
    std::string manoeuvre;  ///< the set's identification train (empty: the scenario's)
  };
  std::vector<Set> sets;
  std::string lateral4_model;
  std::map<std::string, std::string> coupled_models;  ///< table id -> model file
  std::map<std::string, TableSpec> tables;
};

std::string resolve(const std::string& file, const std::string& path) {
  return (fs::path(path).is_absolute() ? fs::path(path) : fs::path(file).parent_path() / path).lexically_normal().string();
}

CampaignSpec load_campaign(const std::string& file) {
  CampaignSpec c;
  c.file = file;
  ConfigMap root = ConfigMap::load_file(file);
  root.get_string("name");
  {
    ConfigMap flights = root.get_map("flights");
    for (const char* name : {"identification", "ol_doublet", "ol_112", "cl_doublet_train", "cl_112", "coupled",
                             "nonlinear_20", "nonlinear_30"}) {
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
  {
    ConfigMap cm = root.get_map("coupled_models");
    for (const char* id : {"13", "14"}) c.coupled_models[id] = resolve(file, cm.get_string(id));
    cm.finish();
  }
  ConfigMap tables = root.get_map("tables");
  for (const char* id : {"9.4", "9.5", "9.6", "8.8", "4", "7", "8", "9", "10", "11", "12", "13", "14", "15", "16"}) {
    ConfigMap t = tables.get_map(id);
    TableSpec s;
    s.title = t.get_string("title");
    s.tolerance.relative = t.get_double_or("relative", 0.0, Range::closed(0.0, 10.0));
    s.tolerance.relative_to_modulus = t.get_double_or("relative_to_modulus", 0.0, Range::closed(0.0, 10.0));
    s.tolerance.sigmas = t.get_double_or("sigmas", 0.0, Range::closed(0.0, 10.0));
    if (t.has("absolute")) {
      ConfigMap a = t.get_map("absolute");
      for (const auto& item : t.get_node("absolute")) {
        const std::string col = item.first.as<std::string>();
        s.tolerance.absolute[col] = a.get_double(col, Range::closed(0.0, 1e6));
      }
      a.finish();
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
      }
      cols.finish();
    }
    if (t.has("explained")) {
      const YAML::Node ex = t.get_node("explained");
      if (!ex.IsMap()) t.fail("explained", "must map \"row / column\" (or \"*\") to a reason");
      for (const auto& item : ex) s.explained[item.first.as<std::string>()] = item.second.as<std::string>();
    }
    t.finish();
    c.tables[id] = s;
  }
  tables.finish();
  root.finish();
  return c;
}

/// A flown flight: its log and the figures of its summary.
struct Flown {
  FlightRecord record;
  double range_p = 0, range_v = 0, range_phi = 0;
};

Flown fly(const CampaignOptions& o, const std::string& name, const std::string& scenario,
          const std::vector<Override>& overrides) {
  Flown f;
  f.record.name = name;
  f.record.scenario = scenario;
  f.record.log = (fs::path(o.work_dir) / (name + ".lcmlog")).string();
  const auto t0 = Clock::now();
  if (o.clock == "inprocess") {
    launcher::RunOptions ro;
    ro.scenario_file = scenario;
    ro.overrides = overrides;
    ro.clock = "inprocess";
    ro.seed = o.seed;
    ro.progress = false;
    ro.print_summary = false;
    const launcher::RunPlan plan = launcher::load_run_plan(ro);
    launcher::InprocessOptions io;
    io.log_file = f.record.log;
    const launcher::RunReport report = launcher::fly_inprocess(plan, io);
    f.record.result = report.verdict.text;
    f.record.controlled = report.verdict.controlled;
    f.record.sim_s = report.sim_time_s;
    f.range_p = report.flight.max_p - report.flight.min_p;
    f.range_v = report.flight.max_v - report.flight.min_v;
    f.range_phi = report.flight.max_phi - report.flight.min_phi;
  } else {
    const std::string json = (fs::path(o.work_dir) / (name + ".json")).string();
    std::string cmd = "'" + o.rig_exe + "' run '" + scenario + "' --clock " + o.clock + " --seed " +
                      std::to_string(o.seed) + " --log '" + f.record.log + "' --json '" + json + "' --no-progress";
    for (const auto& ov : overrides) cmd += " --set '" + ov.key_path + "=" + ov.value + "'";
    cmd += " > '" + (fs::path(o.work_dir) / (name + ".out")).string() + "' 2>&1";
    std::system(cmd.c_str());
    if (!fs::exists(json)) throw std::runtime_error("flight " + name + ": rig run wrote no report (" + cmd + ")");
    const YAML::Node j = YAML::LoadFile(json);
    f.record.result = j["result"].as<std::string>();
    f.record.controlled = j["controlled"].as<bool>();
    f.record.sim_s = j["sim_time_s"].as<double>();
    f.range_p = j["ranges"]["p"].as<double>();
    f.range_v = j["ranges"]["v"].as<double>();
    f.range_phi = j["ranges"]["phi"].as<double>();
  }
  f.record.wall_s = seconds_since(t0);
  if (o.progress) {
    std::cerr << fmt::format("rig reproduce: flew {} ({}) in {:.2f} s: {}\n", name, fs::path(scenario).filename().string(),
                             f.record.wall_s, f.record.result);
  }
  return f;
}

/// The thesis's identification of one flight (WLS, Eq 21 with w0 the flight's initial w), plus
/// the regressor p (w - w0) in the side-force equation.
ident::IdentResult identify_flight(const std::string& log, ident::StateSource states, const Vehicle& vehicle,
                                   const std::string& vehicle_file, const std::string& name) {
  const ident::FlightData data = ident::read_rig_log(log, states).measured;
  ident::IdentOptions opt;
  opt.trim.w0_mps = data.at("w").values.front();
  opt.model_name = name;
  const double w0 = opt.trim.w0_mps, g = vehicle.gravity_mps2;
  opt.add_signals = [w0, g](ident::UniformData& d) {
    d.signals["pw"] = d.at("p").cwiseProduct((d.at("w").array() - w0).matrix());
    d.signals["gphi"] = (g * (d.at("phi").array().sin() - d.at("phi").array())).matrix();
  };
  opt.extra_regressors = {{"Y", "pw"}, {"Y", "gphi"}};
  return ident::identify(data, vehicle, vehicle_file, opt);
}

/// Eigenvalues of a three-state model: the real one and the complex one with positive imaginary part.
std::pair<double, std::complex<double>> split_eigenvalues(const std::vector<std::complex<double>>& eig) {
  double real = NAN;
  std::complex<double> osc(NAN, NAN);
  for (const auto& e : eig) {
    if (std::fabs(e.imag()) < 1e-9) {
      real = e.real();
    } else if (e.imag() > 0) {
      osc = e;
    }
  }
  return {real, osc};
}

/// Standard deviations of the aperiodic eigenvalue and of the oscillatory pair's real and imaginary
/// parts of an identified three-state model: each stability derivative of A moved by its
/// estimate's standard deviation (Newey-West), the changes added in quadrature.
std::array<double, 3> eigenvalue_sigmas(const ident::IdentResult& id) {
  const auto [a0, o0] = split_eigenvalues(id.eigenvalues);
  double va = 0.0, vr = 0.0, vi = 0.0;
  for (const char* name : {"Lp", "Lv", "Yp", "Yv"}) {
    DerivativeModel moved = id.model;
    moved.derivatives[name] += id.parameters.at(name).sigma_coloured;
    const Eigen::VectorXcd eig = build_state_space(moved, id.vehicle).A.eigenvalues();
    const auto [a, o] = split_eigenvalues(std::vector<std::complex<double>>(eig.data(), eig.data() + eig.size()));
    va += (a - a0) * (a - a0);
    vr += (o.real() - o0.real()) * (o.real() - o0.real());
    vi += (o.imag() - o0.imag()) * (o.imag() - o0.imag());
  }
  return {std::sqrt(va), std::sqrt(vr), std::sqrt(vi)};
}

class Judge {
 public:
  Judge(const std::string& id, const TableSpec& spec) : spec_(spec) {
    table_.id = id;
    table_.title = spec.title;
    std::ostringstream t;
    if (spec.tolerance.relative > 0) t << "within " << 100 * spec.tolerance.relative << " % of the published value";
    if (spec.tolerance.relative_to_modulus > 0) {
      t << "within " << 100 * spec.tolerance.relative_to_modulus << " % of the published eigenvalue's modulus";
    }
    for (const auto& [col, a] : spec.tolerance.absolute) t << (t.tellp() > 0 ? "; " : "") << col << " within " << a;
    if (spec.tolerance.sigmas > 0) {
      t << ", or within " << spec.tolerance.sigmas << " standard deviations of the rig's estimate where that is wider";
    }
    table_.tolerance = t.str();
  }
  /// Adds the cell (row, column) with the rig's value; `modulus` for eigenvalue tables, `sigma`
  /// (the standard deviation of the rig's value) for identified parameters.
  void cell(const std::string& row, const std::string& column, double rig, double modulus = NAN, double sigma = NAN) {
    const auto r = spec_.published.find(row);
    if (r == spec_.published.end() || r->second.count(column) == 0) return;  // not published
    Cell c;
    c.row = row;
    c.column = column;
    c.published = r->second.at(column);
    c.rig = rig;
    double allowed = 0.0;
    const auto abs = spec_.tolerance.absolute.find(column);
    if (abs != spec_.tolerance.absolute.end()) {
      allowed = abs->second;
    } else if (spec_.tolerance.relative_to_modulus > 0) {
      allowed = spec_.tolerance.relative_to_modulus * (std::isfinite(modulus) ? modulus : std::fabs(c.published));
    } else {
      allowed = spec_.tolerance.relative * std::fabs(c.published);
    }
    if (spec_.tolerance.sigmas > 0 && std::isfinite(sigma)) allowed = std::max(allowed, spec_.tolerance.sigmas * sigma);
    const bool match = std::isfinite(rig) && std::fabs(rig - c.published) <= allowed;
    if (match) {
      c.verdict = "match";
    } else if (const std::string why = reason(row, column); !why.empty()) {
      c.verdict = "explained";
      c.reason = why;
    } else {
      c.verdict = "differs";
      c.reason = std::isfinite(rig) ? fmt::format("off by {:.3g}, allowed {:.3g}", rig - c.published, allowed)
                                    : "the rig has no value";
    }
    table_.cells.push_back(c);
  }
  Table take() { return std::move(table_); }

 private:
  std::string reason(const std::string& row, const std::string& column) const {
    for (const std::string& key : {row + " / " + column, row + " / *", "* / " + column, std::string("*")}) {
      const auto it = spec_.explained.find(key);
      if (it != spec_.explained.end()) return it->second;
    }
    return "";
  }
  const TableSpec& spec_;
  Table table_;
};

void fit_cells(Judge& j, const std::string& row, const ident::FitMetrics& m) {
  j.cell(row, "rxy", m.rxy);
  j.cell(row, "R2", m.r2);
  j.cell(row, "RMSE %", m.rmse_pct_range);
}

const ident::OutputFit& fit_of(const std::vector<ident::OutputFit>& fits, const std::string& output) {
  for (const auto& f : fits) {
    if (f.output == output) return f;
  }
  throw std::runtime_error("no fit of " + output);
}

/// An open-loop validation table: the state-derivative fits of p, v and phi.
Table open_loop_table(const std::string& id, const TableSpec& spec, const ident::ValidationResult& v) {
  Judge j(id, spec);
  for (const char* out : {"p_dot", "v_dot", "phi_dot"}) fit_cells(j, out, fit_of(v.fits, out).metrics);
  return j.take();
}

/// Fig 9.1: every set's identified eigenvalues with the published ones, on one map.
void plot_eigenvalue_map(const std::string& dir, const std::vector<std::pair<std::string, std::vector<std::complex<double>>>>& rig,
                         const TableSpec& published) {
  std::ostringstream data;
  for (const auto& [row, eig] : rig) {
    for (const auto& e : eig) data << e.real() << " " << e.imag() << "\n";
  }
  data << "\n\n";
  for (const auto& row : published.row_order) {
    const auto& c = published.published.at(row);
    data << c.at("aperiodic") << " 0\n";
    data << c.at("oscillatory re") << " " << c.at("oscillatory im") << "\n";
    data << c.at("oscillatory re") << " " << -c.at("oscillatory im") << "\n";
  }
  const fs::path dat = fs::path(dir) / "eigenvalues_9_1.dat", png = fs::path(dir) / "eigenvalues_9_1.png";
  write_file(dat, data.str());
  ident::run_gnuplot(dir, "eigenvalues_9_1",
                     "set terminal pngcairo size 900,650\nset output " + ident::gp_quote(png.string()) + "\n"
                     "set title 'Eigenvalues of the identified models, every set (thesis Fig 9.1)'\n"
                     "set xlabel 'real part [1/s]'\nset ylabel 'imaginary part [1/s]'\nset grid\n"
                     "set key below\nset xzeroaxis lt -1\nset yzeroaxis lt -1\n"
                     "plot " + ident::gp_quote(dat.string()) + " index 0 with points pt 7 ps 1.5 title 'rig-identified', "
                     "'' index 1 with points pt 6 ps 2 lw 2 title 'published (Table 9.5)'\n");
}

/// Table 9.6: the non-dimensional derivatives of set 1's identified model, thesis Eq 9.2 with
/// Eq 9.3 (f 17 Hz as the thesis, the vehicle's wing data).
Table table_9_6(const CampaignSpec& spec, const ident::IdentResult& id) {
  Judge t96("9.6", spec.tables.at("9.6"));
  const Vehicle& v = id.vehicle;
  const double f = v.flap_frequency_hz, rho = v.air_density_kgpm3, A = v.wing_area_m2, c = v.mean_chord_m;
  const double U = 2.0 * v.flap_amplitude_rad * f * v.r2_m;
  const auto d = [&](const char* name) { return id.parameters.at(name).value; };
  const auto sd = [&](const char* name) { return id.parameters.at(name).sigma_coloured; };
  const std::string row = spec.sets.front().row;
  const double kLp = f / (rho * U * U * A * c), kLv = 1.0 / (rho * U * A * c);
  const double kYp = f / (rho * U * U * A), kYv = 1.0 / (rho * U * A);
  t96.cell(row, "Lp+", d("Lp") * kLp, NAN, sd("Lp") * kLp);
  t96.cell(row, "Lv+", d("Lv") * kLv, NAN, sd("Lv") * kLv);
  t96.cell(row, "Yp+", d("Yp") * kYp, NAN, sd("Yp") * kYp);
  t96.cell(row, "Yv+", d("Yv") * kYv, NAN, sd("Yv") * kYv);
  return t96.take();
}

/// Table 8.8: the eigenvalues of the four-state model file.
Table table_8_8(const CampaignSpec& spec) {
  const DerivativeModel lat4 = load_model(spec.lateral4_model);
  const StateSpace ss = build_state_space(lat4, load_vehicle(lat4.vehicle_file));
  const Eigen::VectorXcd eig = ss.A.eigenvalues();
  double stable = NAN, unstable = NAN;
  std::complex<double> osc(NAN, NAN);
  for (int i = 0; i < eig.size(); ++i) {
    if (std::fabs(eig(i).imag()) > 1e-9) {
      if (eig(i).imag() > 0) osc = eig(i);
    } else if (eig(i).real() < 0) {
      stable = eig(i).real();
    } else {
      unstable = eig(i).real();
    }
  }
  Judge j("8.8", spec.tables.at("8.8"));
  const auto& pub = spec.tables.at("8.8").published.at("lateral4");
  const double modulus = std::abs(std::complex<double>(pub.at("oscillatory re"), pub.at("oscillatory im")));
  j.cell("lateral4", "aperiodic stable", stable);
  j.cell("lateral4", "oscillatory re", osc.real(), modulus);
  j.cell("lateral4", "oscillatory im", osc.imag(), modulus);
  j.cell("lateral4", "aperiodic unstable", unstable);
  return j.take();
}

}  // namespace

std::map<std::string, int> CampaignResult::counts() const {
  std::map<std::string, int> c{{"match", 0}, {"explained", 0}, {"differs", 0}};
  for (const auto& t : tables) {
    for (const auto& cell : t.cells) ++c[cell.verdict];
  }
  return c;
}

CampaignResult run_campaign(const CampaignOptions& o) {
  const auto t0 = Clock::now();
  const CampaignSpec spec = load_campaign(o.campaign_file);
  fs::create_directories(o.work_dir);
  if (!o.report_dir.empty()) {
    ident::require_gnuplot();
    fs::create_directories(o.report_dir);
  }
  const ident::StateSource states = o.states == "truth" ? ident::StateSource::kTruth : ident::StateSource::kAuto;
  CampaignResult result;
  result.states = o.states;
  result.campaign = o.campaign_file;
  result.clock = o.clock;
  result.seed = o.seed;

  // Identification flights of every set: Tables 9.4, 9.5 (and 9.6, 4 from set 1).
  Judge t94("9.4", spec.tables.at("9.4")), t95("9.5", spec.tables.at("9.5"));
  Judge t4("4", spec.tables.at("4"));
  std::optional<ident::IdentResult> set1;
  std::string set1_log;
  std::vector<std::pair<std::string, std::vector<std::complex<double>>>> all_eigenvalues;
  for (const auto& [row, model_file, manoeuvre] : spec.sets) {
    const std::string flight_name = "identification_" + row.substr(row.rfind(' ') + 1);
    std::vector<Override> overrides{{"model", model_file}};
    if (!manoeuvre.empty()) overrides.push_back({"manoeuvre", manoeuvre});
    const Flown f = fly(o, row == spec.sets.front().row ? "identification" : flight_name,
                        spec.flights.at("identification"), overrides);
    result.flights.push_back(f.record);
    t94.cell(row, "p", f.range_p);
    t94.cell(row, "v", f.range_v);
    t94.cell(row, "phi", f.range_phi);
    const DerivativeModel truth = load_model(model_file);
    const Vehicle vehicle = load_vehicle(truth.vehicle_file);
    ident::IdentResult id = identify_flight(f.record.log, states, vehicle, truth.vehicle_file, "rig_" + row);
    const auto [aperiodic, osc] = split_eigenvalues(id.eigenvalues);
    const std::array<double, 3> sd = eigenvalue_sigmas(id);
    t95.cell(row, "aperiodic", aperiodic, std::fabs(spec.tables.at("9.5").published.at(row).at("aperiodic")), sd[0]);
    const auto& pub = spec.tables.at("9.5").published.at(row);
    const double modulus = std::abs(std::complex<double>(pub.at("oscillatory re"), pub.at("oscillatory im")));
    t95.cell(row, "oscillatory re", osc.real(), modulus, sd[1]);
    t95.cell(row, "oscillatory im", osc.imag(), modulus, sd[2]);
    all_eigenvalues.emplace_back(row, id.eigenvalues);
    if (!set1) {
      set1 = std::move(id);
      set1_log = f.record.log;
    }
  }
  result.tables.push_back(t94.take());
  result.tables.push_back(t95.take());

  result.tables.push_back(table_9_6(spec, *set1));
  fit_cells(t4, "p_dot", fit_of(set1->fits, "p_dot").metrics);
  fit_cells(t4, "v_dot", fit_of(set1->fits, "v_dot_star").metrics);
  result.tables.push_back(t4.take());

  const DerivativeModel& model = set1->model;
  const Vehicle& vehicle = set1->vehicle;
  // Open-loop validation: Tables 7, 8, 15, 16.
  for (const auto& [id, flight] : std::vector<std::pair<std::string, std::string>>{
           {"7", "ol_doublet"}, {"8", "ol_112"}, {"15", "nonlinear_30"}, {"16", "nonlinear_20"}}) {
    const Flown f = fly(o, flight, spec.flights.at(flight), {});
    result.flights.push_back(f.record);
    const ident::ValidationResult v =
        ident::validate_open_loop(ident::read_rig_log(f.record.log, states).measured, model, vehicle,
                                  ident::ValidationOptions{});
    result.tables.push_back(open_loop_table(id, spec.tables.at(id), v));
    if (!o.report_dir.empty()) {
      const fs::path dir = fs::path(o.report_dir) / ("table_" + id + "_" + flight);
      fs::create_directories(dir);
      ident::plot_validation(v, dir.string());
    }
  }

  // Closed-loop validation: Tables 9 (the identification flight), 10, 11, with the gains each flew.
  const ControllerConfig controller = load_controller_config(o.controller_file);
  for (const auto& [id, flight] : std::vector<std::pair<std::string, std::string>>{
           {"9", "identification"}, {"10", "cl_doublet_train"}, {"11", "cl_112"}}) {
    std::string log = set1_log, gains;
    if (flight != "identification") {
      const Flown f = fly(o, flight, spec.flights.at(flight), {});
      result.flights.push_back(f.record);
      log = f.record.log;
    }
    const ident::RigLogData data = ident::read_rig_log(log, states);
    ident::ClosedLoopOptions cl;
    cl.controller = controller;
    cl.gain_set = data.gain_set.empty() ? "fast" : data.gain_set;
    const ident::ClosedLoopResult r = ident::validate_closed_loop(data.measured, model, vehicle, cl);
    Judge j(id, spec.tables.at(id));
    for (const char* s : {"p", "v", "phi", "delta_f"}) fit_cells(j, s, r.fits.at(s));
    result.tables.push_back(j.take());
    if (!o.report_dir.empty()) {
      const fs::path dir = fs::path(o.report_dir) / ("table_" + id + "_" + flight);
      fs::create_directories(dir);
      ident::plot_closed_loop(r, dir.string());
    }
  }
  // The coupled doublet: set 1's identified model (Table 12) and the reduced models of Tables B.1
  // and B.2 as published (Tables 13, 14).
  {
    const Flown f = fly(o, "coupled", spec.flights.at("coupled"), {});
    result.flights.push_back(f.record);
    const ident::FlightData data = ident::read_rig_log(f.record.log, states).measured;
    for (const auto& [id, file] : std::vector<std::pair<std::string, std::string>>{
             {"12", ""}, {"13", spec.coupled_models.at("13")}, {"14", spec.coupled_models.at("14")}}) {
      const DerivativeModel m = file.empty() ? model : load_model(file);
      const ident::ValidationResult v =
          ident::validate_open_loop(data, m, file.empty() ? vehicle : load_vehicle(m.vehicle_file), ident::ValidationOptions{});
      result.tables.push_back(open_loop_table(id, spec.tables.at(id), v));
    }
  }

  result.tables.push_back(table_8_8(spec));  // the four-state model file
  if (!o.report_dir.empty()) {
    plot_eigenvalue_map(o.report_dir, all_eigenvalues, spec.tables.at("9.5"));
    const fs::path dir = fs::path(o.report_dir) / "identification_set_1";
    fs::create_directories(dir);
    ident::plot_identification(*set1, dir.string());
  }
  result.wall_s = seconds_since(t0);
  return result;
}

std::string campaign_text(const CampaignResult& r) {
  std::ostringstream out;
  out << fmt::format("== rig reproduce thesis: {} flights, clock {}, seed {}, states from {}, {:.1f} s ==\n",
                     r.flights.size(), r.clock, r.seed, r.states, r.wall_s);
  for (const auto& f : r.flights) {
    out << fmt::format("  {:<26} {:<32} {}\n", f.name, fs::path(f.scenario).filename().string(), f.result);
  }
  for (const auto& t : r.tables) {
    out << fmt::format("\nTable {}: {}\n  match: {}\n", t.id, t.title, t.tolerance);
    out << fmt::format("  {:<10} {:<20} {:>11} {:>11}  {}\n", "row", "column", "published", "rig", "verdict");
    // A table's reasons once each, as notes below it.
    std::vector<std::string> notes;
    for (const auto& c : t.cells) {
      std::string note;
      if (c.verdict == "explained") {
        auto it = std::find(notes.begin(), notes.end(), c.reason);
        if (it == notes.end()) it = notes.insert(notes.end(), c.reason);
        note = fmt::format(" [{}]", it - notes.begin() + 1);
      } else if (!c.reason.empty()) {
        note = " (" + c.reason + ")";
      }
      out << fmt::format("  {:<10} {:<20} {:>11.4g} {:>11.4g}  {}{}\n", c.row, c.column, c.published, c.rig, c.verdict,
                         note);
    }
    for (std::size_t i = 0; i < notes.size(); ++i) out << fmt::format("  [{}] {}\n", i + 1, notes[i]);
  }
  const auto counts = r.counts();
  const int total = counts.at("match") + counts.at("explained") + counts.at("differs");
  out << fmt::format("\ncells: {} match, {} explained, {} differ, of {} ({:.0f} % match)\n", counts.at("match"),
                     counts.at("explained"), counts.at("differs"), total,
                     total > 0 ? 100.0 * counts.at("match") / total : 0.0);
  return out.str();
}

std::string campaign_json(const CampaignResult& r) {
  JsonWriter w;
  w.begin_object();
  w.key("campaign").value(r.campaign).key("clock").value(r.clock).key("seed").value(static_cast<long long>(r.seed));
  w.key("states").value(r.states);
  w.key("wall_s").value(r.wall_s);
  w.key("flights").begin_array();
  for (const auto& f : r.flights) {
    w.begin_object().key("name").value(f.name).key("scenario").value(f.scenario).key("log").value(f.log);
    w.key("result").value(f.result).key("controlled").value(f.controlled).key("sim_s").value(f.sim_s);
    w.key("wall_s").value(f.wall_s).end_object();
  }
  w.end_array();
  w.key("tables").begin_array();
  for (const auto& t : r.tables) {
    w.begin_object().key("id").value(t.id).key("title").value(t.title).key("tolerance").value(t.tolerance);
    w.key("cells").begin_array();
    for (const auto& c : t.cells) {
      w.begin_object().key("row").value(c.row).key("column").value(c.column);
      w.key("published").value(c.published).key("rig").value(c.rig).key("verdict").value(c.verdict);
      w.key("reason").value(c.reason).end_object();
    }
    w.end_array().end_object();
  }
  w.end_array();
  w.key("counts").begin_object();
  for (const auto& [k, n] : r.counts()) w.key(k).value(n);
  w.end_object();
  w.end_object();
  return w.str();
}

}  // namespace nimble::reproduce
