/// `rig reproduce thesis --beside` (reproduce/beside.h).

#include "reproduce/beside.h"
#include "core/json_line.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <sstream>
#include <stdexcept>

#include <fmt/format.h>

namespace nimble::reproduce {
namespace {

namespace fs = std::filesystem;

std::string join(const std::vector<std::string>& v, const char* sep) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : sep) + x;
  return s;
}

std::string seed_list_text(const std::vector<std::uint64_t>& seeds) {
  std::string s;
  for (std::size_t i = 0; i < seeds.size(); ++i) s += (i ? "," : "") + std::to_string(seeds[i]);
  return s;
}

/// A cell counts unless it repeats an earlier cell's numbers in both runs.
bool counted(const BesideCell& c) { return c.without.repeats.empty() || c.with.repeats.empty(); }

/// `dir`/`sub`, or empty for an empty `dir`.
std::string sub_dir(const std::string& dir, const char* sub) {
  return dir.empty() ? std::string() : (fs::path(dir) / sub).string();
}

/// The note one run's cell carries, numbered among the table's `notes` (text repeated once):
/// what an explained cell's reason and check are, why a differing cell's reason does not hold,
/// why a cell is inconclusive (too few seeds, or its interval across an edge of the band, with the
/// seeds that would decide it), what a calibrated cell was tuned on. A cell that differs without a
/// reason carries none: its line shows the numbers, the interval and the tolerance.
std::string side_note(const std::string& table_category, const Cell& c, std::vector<std::string>& notes) {
  std::string text;
  if (c.verdict == "explained") {
    text = c.reason + " [check: " + c.check.predicate + "; found: " + c.check.value + "]";
  } else if ((c.verdict == "differs" && c.has_check) || c.verdict == "inconclusive") {
    text = c.reason;
  } else if (c.category == "calibrated" && !c.reason.empty() && table_category != "calibrated") {
    text = "calibrated: " + c.reason;
  }
  if (text.empty()) return "";
  auto it = std::find(notes.begin(), notes.end(), text);
  if (it == notes.end()) it = notes.insert(notes.end(), text);
  return fmt::format("[{}]", it - notes.begin() + 1);
}

/// "n flights, w s; flights not ok: k" and each flight not ok, for one run.
void run_lines(std::ostringstream& out, const char* label, const CampaignResult& r) {
  int failed = 0;
  for (const auto& f : r.flights) failed += f.result == "ok" ? 0 : 1;
  out << fmt::format("  {}: {} flights, {:.1f} s; flights not ok: {}\n", label, r.flights.size(), r.wall_s, failed);
  for (const auto& f : r.flights) {
    if (f.result != "ok") out << fmt::format("    {} seed {}: {}\n", f.name, f.seed, f.result);
  }
}

void table_text(std::ostringstream& out, const BesideTable& t) {
  out << fmt::format("\nTable {}: {}  [{}]\n", t.id, t.title, t.category);
  if (!t.why.empty()) out << "  " << t.why << "\n";
  out << fmt::format("  {:<10} {:<16} {:>10} {:>9}  {:>10} {:>9} {:<14}  {:>10} {:>9} {:<14}  {:<6}  {}\n", "row",
                     "column", "published", "tol", "without", "+-95%", "verdict", "with", "+-95%", "verdict", "moved",
                     "notes (without / with)");
  std::vector<std::string> notes;
  for (const auto& c : t.cells) {
    const std::string a = side_note(t.category, c.without, notes), b = side_note(t.category, c.with, notes);
    std::string note = a.empty() && b.empty() ? "" : (a.empty() ? "-" : a) + " / " + (b.empty() ? "-" : b);
    if (!c.without.repeats.empty() && !c.with.repeats.empty()) note += " (repeats " + c.without.repeats + ")";
    const std::string line = fmt::format(
        "  {:<10} {:<16} {:>10.4g} {:>9.3g}  {:>10.4g} {:>9.2g} {:<14}  {:>10.4g} {:>9.2g} {:<14}  {:<6}  {}",
        c.without.row, c.without.column, c.without.published, c.without.tolerance, c.without.rig, c.without.interval,
        c.without.verdict, c.with.rig, c.with.interval, c.with.verdict, c.moved, note);
    out << line.substr(0, line.find_last_not_of(' ') + 1) << "\n";
  }
  for (std::size_t i = 0; i < notes.size(); ++i) out << fmt::format("  [{}] {}\n", i + 1, notes[i]);
}

/// The identified derivatives against the plant's in both runs (not thesis cells).
void plant_check_text(std::ostringstream& out, const BesideResult& r) {
  if (r.without.plant_check.size() != r.with.plant_check.size() || r.with.plant_check.empty()) return;
  out << fmt::format("\nThe identification against the plant (not a thesis cell; states {}, mean over the seeds)\n",
                     r.with.states);
  out << fmt::format("  {:<7} {:<10} {:>11}  {:>11} {:>9} {:>8}  {:>11} {:>9} {:>8}\n", "row", "derivative", "plant",
                     "without", "+-95%", "error", "with", "+-95%", "error");
  for (std::size_t i = 0; i < r.with.plant_check.size(); ++i) {
    const PlantCheck& a = r.without.plant_check[i];
    const PlantCheck& b = r.with.plant_check[i];
    const std::string derivative = a.derivative + (a.method == "output error" ? " (OE)" : "");
    out << fmt::format("  {:<7} {:<10} {:>11.4g}  {:>11.4g} {:>9.2g} {:>7.1f}%  {:>11.4g} {:>9.2g} {:>7.1f}%\n", a.row,
                       derivative, a.plant, a.mean, a.interval, 100 * (a.mean / a.plant - 1), b.mean, b.interval,
                       100 * (b.mean / b.plant - 1));
  }
}

/// "n a, m b" of a count map, with the total; the keys in `first` first, in that order.
std::string count_line(const std::map<std::string, int>& counts, const std::vector<std::string>& first = {}) {
  std::vector<std::string> order = first;
  for (const auto& [what, n] : counts) {
    if (std::find(order.begin(), order.end(), what) == order.end()) order.push_back(what);
  }
  std::string line;
  int total = 0;
  for (const auto& what : order) {
    const auto it = counts.find(what);
    if (it == counts.end()) continue;
    line += fmt::format("{}{} {}", line.empty() ? "" : ", ", it->second, what);
    total += it->second;
  }
  return fmt::format("{} (of {})", line, total);
}

OrderedJson cell_json(const OrderedJson& side_table, std::size_t k) { return side_table.at("cells").at(k); }

/// A double as JSON: null for NaN or infinity, as the campaign's JSON writes them.
OrderedJson json_number(double x) { return std::isfinite(x) ? OrderedJson(x) : OrderedJson(nullptr); }

}  // namespace

std::string moved(const Cell& without, const Cell& with) {
  if (!std::isfinite(without.rig) || !std::isfinite(with.rig) || !std::isfinite(without.reference)) return "n/a";
  const double before = std::fabs(without.rig - without.reference), after = std::fabs(with.rig - with.reference);
  const double bound = std::max({without.tolerance, with.tolerance, std::hypot(without.interval, with.interval)});
  if (std::fabs(after - before) <= bound) return "same";
  return after < before ? "toward" : "away";
}

std::map<std::string, std::map<std::string, int>> BesideResult::moved_counts() const {
  std::map<std::string, std::map<std::string, int>> out;
  for (const auto& t : tables) {
    for (const auto& c : t.cells) {
      if (counted(c)) ++out[c.without.category][c.moved];
    }
  }
  return out;
}

std::map<std::string, std::map<std::string, int>> BesideResult::verdict_changes() const {
  std::map<std::string, std::map<std::string, int>> out;
  for (const auto& t : tables) {
    for (const auto& c : t.cells) {
      if (counted(c) && c.without.verdict != c.with.verdict) {
        ++out[c.without.category][c.without.verdict + " -> " + c.with.verdict];
      }
    }
  }
  return out;
}

BesideResult merge_beside(CampaignResult without, CampaignResult with) {
  BesideResult r;
  if (without.tables.size() != with.tables.size()) {
    throw std::runtime_error(fmt::format("the runs have {} and {} tables", without.tables.size(), with.tables.size()));
  }
  for (std::size_t i = 0; i < without.tables.size(); ++i) {
    const Table& a = without.tables[i];
    const Table& b = with.tables[i];
    if (a.id != b.id || a.cells.size() != b.cells.size()) {
      throw std::runtime_error("the runs' table " + a.id + " and " + b.id + " differ in their cells");
    }
    BesideTable t{a.id, a.title, a.category, a.why, {}};
    for (std::size_t k = 0; k < a.cells.size(); ++k) {
      const Cell& x = a.cells[k];
      const Cell& y = b.cells[k];
      if (x.row != y.row || x.column != y.column) {
        throw std::runtime_error("table " + a.id + ": cell " + x.row + " / " + x.column + " beside " + y.row + " / " +
                                 y.column);
      }
      t.cells.push_back({x, y, moved(x, y)});
    }
    r.tables.push_back(std::move(t));
  }
  r.without = std::move(without);
  r.with = std::move(with);
  return r;
}

BesideResult run_beside(const CampaignOptions& o) {
  if (o.overrides.empty()) throw std::invalid_argument("--beside needs overrides (--set or --vibration) to fly beside");
  std::error_code ec;
  if (!o.result_dir.empty() && fs::exists(fs::path(o.result_dir) / "campaign.json", ec)) {
    throw std::runtime_error(o.result_dir + " holds one campaign; --beside keeps its two in " + o.result_dir +
                             "/without and " + o.result_dir + "/with");
  }
  CampaignOptions without = o, with = o;
  without.overrides.clear();
  for (auto [run, sub] : {std::pair{&without, "without"}, std::pair{&with, "with"}}) {
    run->work_dir = sub_dir(o.work_dir, sub);
    run->report_dir = sub_dir(o.report_dir, sub);
    run->result_dir = sub_dir(o.result_dir, sub);
  }
  CampaignResult a = run_campaign(without);
  return merge_beside(std::move(a), run_campaign(with));
}

std::string beside_text(const BesideResult& r) {
  std::ostringstream out;
  out << fmt::format("== rig reproduce thesis, without and with overrides: clock {}, seeds {}, states {} ==\n",
                     r.with.clock, seed_list_text(r.with.seeds), r.with.states);
  out << "  overrides (every flight of the second run): " << join(r.with.overrides, ", ") << "\n";
  run_lines(out, "without", r.without);
  run_lines(out, "with", r.with);
  for (const auto& t : r.tables) table_text(out, t);
  plant_check_text(out, r);
  out << "\ncells by category and verdict (a cell repeating another's numbers counted once):\n";
  for (const auto* run : {&r.without, &r.with}) {
    out << (run == &r.without ? "  without\n" : "  with\n");
    for (const auto& [category, verdicts] : run->counts()) {
      out << fmt::format("    {:<15} {}\n", category, count_line(verdicts));
    }
  }
  out << "\nmoved against the value judged against (published; a pipeline check's plant file), without -> with "
         "(|rig - reference|; same: within the tolerance or the two means' 95 % interval):\n";
  const auto changes = r.verdict_changes();
  for (const auto& [category, counts] : r.moved_counts()) {
    out << fmt::format("  {:<15} {}\n", category, count_line(counts, {"toward", "away", "same"}));
    const auto it = changes.find(category);
    out << fmt::format("  {:<15} verdicts changed: {}\n", "", it == changes.end() ? "none" : count_line(it->second));
  }
  return out.str();
}

std::string beside_json(const BesideResult& r) {
  const OrderedJson without = OrderedJson::parse(campaign_json(r.without)),
                    with = OrderedJson::parse(campaign_json(r.with));
  OrderedJson j;
  j["beside"] = true;
  j["overrides"] = r.with.overrides;
  j["tables"] = OrderedJson::array();
  for (std::size_t i = 0; i < r.tables.size(); ++i) {
    const BesideTable& t = r.tables[i];
    OrderedJson cells = OrderedJson::array();
    for (std::size_t k = 0; k < t.cells.size(); ++k) {
      const BesideCell& c = t.cells[k];
      cells.push_back({{"row", c.without.row},
                       {"column", c.without.column},
                       {"published", json_number(c.without.published)},
                       {"tolerance", json_number(c.without.tolerance)},
                       {"category", c.without.category},
                       {"rig_without", json_number(c.without.rig)},
                       {"rig_with", json_number(c.with.rig)},
                       {"interval_without", json_number(c.without.interval)},
                       {"interval_with", json_number(c.with.interval)},
                       {"verdict_without", c.without.verdict},
                       {"verdict_with", c.with.verdict},
                       {"moved", c.moved},
                       {"without", cell_json(without.at("tables").at(i), k)},
                       {"with", cell_json(with.at("tables").at(i), k)}});
    }
    j["tables"].push_back(
        {{"id", t.id}, {"title", t.title}, {"category", t.category}, {"why", t.why}, {"cells", cells}});
  }
  j["moved"] = r.moved_counts();
  j["verdict_changes"] = r.verdict_changes();
  j["without"] = without;
  j["with"] = with;
  return json_line(j);
}

}  // namespace nimble::reproduce
