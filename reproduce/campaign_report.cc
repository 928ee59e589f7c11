/// `rig reproduce thesis`'s tables as text and JSON, and the counts by category and verdict.

#include <algorithm>
#include <complex>
#include <filesystem>
#include <sstream>

#include <fmt/format.h>

#include "core/output_file.h"
#include "ident/plots.h"
#include "reproduce/thesis_campaign.h"
#include "plots/gnuplot.h"
#include "core/json_line.h"

namespace nimble::reproduce {
namespace {

/// Share of `match` among the judged cells of the rig's own flights (repeats counted once).
double match_share(const CampaignResult& r) {
  const auto counts = r.counts();
  const auto it = counts.find("flights");
  if (it == counts.end()) return 0.0;
  int total = 0;
  for (const auto& [verdict, n] : it->second) total += verdict == "not judged" ? 0 : n;
  const auto m = it->second.find("match");
  return total > 0 && m != it->second.end() ? static_cast<double>(m->second) / total : 0.0;
}

/// The bases of a table's tolerances, each with the cells it holds for (all of them: "every cell").
std::string tolerance_bases(const Table& t) {
  std::vector<std::pair<std::string, std::vector<std::string>>> bases;
  for (const auto& c : t.cells) {
    auto it = std::find_if(bases.begin(), bases.end(), [&](const auto& b) { return b.first == c.tolerance_basis; });
    if (it == bases.end()) it = bases.insert(bases.end(), {c.tolerance_basis, {}});
    it->second.push_back(c.row + " / " + c.column);
  }
  std::string out;
  for (const auto& [basis, cells] : bases) {
    std::string list;
    for (const auto& cell : cells) list += (list.empty() ? "" : ", ") + cell;
    out += (out.empty() ? "" : "; ") + basis + (bases.size() == 1 ? " (every cell)" : " (" + list + ")");
  }
  return out;
}

std::string seeds_text(const std::vector<std::uint64_t>& seeds) {
  std::string s;
  for (std::size_t i = 0; i < seeds.size(); ++i) s += (i ? "," : "") + std::to_string(seeds[i]);
  return s;
}

}  // namespace

std::map<std::string, std::map<std::string, int>> CampaignResult::counts() const {
  std::map<std::string, std::map<std::string, int>> c;
  for (const auto& t : tables) {
    for (const auto& cell : t.cells) {
      if (cell.repeats.empty()) ++c[cell.category][cell.verdict];
    }
  }
  return c;
}

int CampaignResult::differing() const {
  int n = 0;
  for (const auto& t : tables) {
    for (const auto& cell : t.cells) n += cell.verdict == "differs" ? 1 : 0;  // a repeat differs too
  }
  return n;
}

std::string campaign_text(const CampaignResult& r) {
  namespace fs = std::filesystem;
  std::ostringstream out;
  out << fmt::format("== rig reproduce thesis: {} flights, clock {}, seeds {}, states {}, {:.1f} s ==\n",
                     r.flights.size(), r.clock, seeds_text(r.seeds), r.states, r.wall_s);
  if (!r.overrides.empty()) {
    std::string ov;
    for (const auto& o : r.overrides) ov += (ov.empty() ? "" : ", ") + o;
    out << "  overrides (every flight): " << ov << "\n";
  }
  int failed = 0;
  for (const auto& f : r.flights) failed += f.result == "ok" ? 0 : 1;
  out << fmt::format("  flights not ok: {}\n", failed);
  for (const auto& f : r.flights) {
    if (f.result != "ok") out << fmt::format("  {} seed {}: {}\n", f.name, f.seed, f.result);
  }
  for (const auto& t : r.tables) {
    out << fmt::format("\nTable {}: {}  [{}]\n", t.id, t.title, t.category);
    if (!t.why.empty()) out << "  " << t.why << "\n";
    out << "  tolerance: " << tolerance_bases(t) << "\n";
    // A pipeline check is judged against the plant file's value, printed beside the thesis's.
    const bool pipeline = t.against_plant;
    out << fmt::format("  {:<10} {:<16} {:>10} {:>10} {:>10} {:>9} {:>9}  {}\n", "row", "column", "published",
                       pipeline ? "plant" : "", "rig", "+-95%", "tol", "verdict");
    std::vector<std::string> notes;
    for (const auto& c : t.cells) {
      std::string note;
      if (!c.repeats.empty()) note = " (repeats " + c.repeats + ")";
      const bool tuned = c.category == "calibrated" && !c.reason.empty() && t.category != "calibrated";
      if (c.verdict == "explained" || (c.verdict == "differs" && c.has_check) || tuned) {
        const std::string text = c.verdict == "explained"
                                     ? c.reason + " [check: " + c.check.predicate + "; found: " + c.check.value + "]"
                                     : c.reason;
        if (tuned) note += " calibrated";
        auto it = std::find(notes.begin(), notes.end(), text);
        if (it == notes.end()) it = notes.insert(notes.end(), text);
        note += fmt::format(" [{}]", it - notes.begin() + 1);
      } else if (!c.reason.empty()) {
        note += " (" + c.reason + ")";
      }
      out << fmt::format("  {:<10} {:<16} {:>10.4g} {:>10} {:>10.4g} {:>9.2g} {:>9.3g}  {}{}\n", c.row, c.column,
                         c.published, pipeline ? fmt::format("{:.4g}", c.reference) : "", c.rig, c.interval,
                         c.tolerance, c.verdict, note);
    }
    for (std::size_t i = 0; i < notes.size(); ++i) out << fmt::format("  [{}] {}\n", i + 1, notes[i]);
  }
  if (!r.plant_check.empty()) {
    out << fmt::format(
        "\nThe identification against the plant (not a thesis cell: each set's flight flew that set's "
        "model; states {}, mean over the seeds)\n",
        r.states);
    out << "  (sd: seed to seed; own sd: the method's own standard deviation of one flight's estimate, coloured "
           "residuals, mean over the seeds)\n";
    out << fmt::format("  {:<7} {:<10} {:<15} {:>11} {:>11} {:>9} {:>9} {:>9} {:>8}\n", "row", "derivative", "method",
                       "plant", "identified", "sd", "own sd", "+-95%", "error");
    for (const auto& c : r.plant_check) {
      out << fmt::format("  {:<7} {:<10} {:<15} {:>11.4g} {:>11.4g} {:>9.2g} {:>9.2g} {:>9.2g} {:>7.1f}%\n", c.row,
                         c.derivative, c.method, c.plant, c.mean, c.sd, c.own_sd, c.interval,
                         100 * (c.mean / c.plant - 1));
    }
  }
  if (!r.causes.empty()) {
    out << "\nWhat the closed-loop tables would need: Tables 9-11 flown again with each cause the thesis gives\n"
           "for its closed-loop misfit, sized from elsewhere (R2; mean over the seeds)\n";
    for (const auto& s : r.causes) {
      std::string ov;
      for (const auto& o : s.overrides) ov += (ov.empty() ? "" : ", ") + o;
      out << fmt::format("  {} ({}; {})\n", s.name, s.source, ov);
      for (const auto& f : s.failures) out << "    not as asked: " << f << "\n";
      out << fmt::format("    {:<6} {:<8} {:>10} {:>10} {:>12} {:>8}  {}\n", "table", "row", "published", "rig",
                         "with cause", "+-95%", "moved");
      for (const auto& c : s.cells) {
        const double before = std::fabs(c.rig - c.published), after = std::fabs(c.with_cause - c.published);
        out << fmt::format("    {:<6} {:<8} {:>10.3g} {:>10.3g} {:>12.3g} {:>8.2g}  {}\n", c.table, c.row, c.published,
                           c.rig, c.with_cause, c.interval,
                           after < before ? fmt::format("toward, {:.0f} % of the gap", 100 * (before - after) / before)
                                          : fmt::format("away, by {:.3g}", after - before));
      }
    }
  }
  out << "\ncells by category and verdict (a cell repeating another's numbers counted once):\n";
  for (const auto& [category, verdicts] : r.counts()) {
    std::string line;
    int total = 0;
    for (const auto& [verdict, n] : verdicts) {
      line += fmt::format("{}{} {}", line.empty() ? "" : ", ", n, verdict);
      total += n;
    }
    out << fmt::format("  {:<15} {} (of {})\n", category, line, total);
  }
  out << fmt::format("match share of the rig's own flights: {:.0f} %\n", 100 * match_share(r));
  return out.str();
}

std::string campaign_json(const CampaignResult& r) {
  OrderedJson j = {{"campaign", r.campaign}, {"clock", r.clock},         {"seeds", r.seeds},
                   {"states", r.states},     {"overrides", r.overrides}, {"wall_s", r.wall_s}};
  j["flights"] = OrderedJson::array();
  for (const auto& f : r.flights) {
    j["flights"].push_back({{"name", f.name},
                            {"seed", f.seed},
                            {"scenario", f.scenario},
                            {"log", f.log},
                            {"result", f.result},
                            {"controlled", f.controlled},
                            {"sim_s", f.sim_s},
                            {"wall_s", f.wall_s}});
  }
  j["tables"] = OrderedJson::array();
  for (const auto& t : r.tables) {
    OrderedJson cells = OrderedJson::array();
    for (const auto& c : t.cells) {
      OrderedJson cell = {{"row", c.row},
                          {"column", c.column},
                          {"published", c.published},
                          {"reference", c.reference},
                          {"rig", c.rig},
                          {"rig_sd", c.rig_sd},
                          {"values", c.values},
                          {"interval", c.interval},
                          {"seeds", c.seeds},
                          {"seeds_to_decide", c.seeds_to_decide},
                          {"tolerance", c.tolerance},
                          {"tolerance_basis", c.tolerance_basis},
                          {"category", c.category},
                          {"verdict", c.verdict},
                          {"reason", c.reason}};
      if (c.has_check) {
        cell["check"] = {{"predicate", c.check.predicate}, {"holds", c.check.holds}, {"value", c.check.value}};
      }
      cell["repeats"] = c.repeats;
      cells.push_back(std::move(cell));
    }
    j["tables"].push_back({{"id", t.id},
                           {"title", t.title},
                           {"category", t.category},
                           {"why", t.why},
                           {"against", t.against_plant ? "plant file" : "published"},
                           {"cells", std::move(cells)}});
  }
  j["causes"] = OrderedJson::array();
  for (const auto& s : r.causes) {
    OrderedJson cells = OrderedJson::array();
    for (const auto& c : s.cells) {
      cells.push_back({{"table", c.table},
                       {"row", c.row},
                       {"column", c.column},
                       {"published", c.published},
                       {"rig", c.rig},
                       {"with_cause", c.with_cause},
                       {"interval", c.interval}});
    }
    j["causes"].push_back({{"name", s.name},
                           {"source", s.source},
                           {"overrides", s.overrides},
                           {"failures", s.failures},
                           {"cells", std::move(cells)}});
  }
  j["plant_check"] = OrderedJson::array();
  for (const auto& c : r.plant_check) {
    j["plant_check"].push_back({{"row", c.row},
                                {"derivative", c.derivative},
                                {"method", c.method},
                                {"plant", c.plant},
                                {"mean", c.mean},
                                {"sd", c.sd},
                                {"own_sd", c.own_sd},
                                {"interval", c.interval}});
  }
  j["counts"] = OrderedJson::object();
  for (const auto& [category, verdicts] : r.counts()) {
    OrderedJson& of = j["counts"][category];
    of = OrderedJson::object();
    for (const auto& [verdict, n] : verdicts) of[verdict] = n;
  }
  j["match_share"] = match_share(r);
  return json_line(j);
}

/// Fig 9.1: every set's identified eigenvalues with the published ones, on one map.
void plot_eigenvalue_map(const std::string& dir,
                         const std::vector<std::pair<std::string, std::vector<std::complex<double>>>>& rig,
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
  const std::filesystem::path dat = std::filesystem::path(dir) / "eigenvalues_9_1.dat",
                              png = std::filesystem::path(dir) / "eigenvalues_9_1.png";
  write_file(dat, data.str());
  plots::run_gnuplot(dir, "eigenvalues_9_1",
                     "set terminal pngcairo size 900,650\nset output " + plots::gp_quote(png.string()) +
                         "\n"
                         "set title 'Eigenvalues of the identified models, every set (thesis Fig 9.1)'\n"
                         "set xlabel 'real part [1/s]'\nset ylabel 'imaginary part [1/s]'\nset grid\n"
                         "set key below\nset xzeroaxis lt -1\nset yzeroaxis lt -1\n"
                         "plot " +
                         plots::gp_quote(dat.string()) +
                         " index 0 with points pt 7 ps 1.5 title 'rig-identified', "
                         "'' index 1 with points pt 6 ps 2 lw 2 title 'published (Table 9.5)'\n");
}

}  // namespace nimble::reproduce
