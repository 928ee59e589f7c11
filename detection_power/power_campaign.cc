#include "detection_power/power_campaign.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <optional>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "core/config.h"
#include "detection_power/effect_size.h"
#include "scenario/scenario.h"
#include "detection_power/record_length.h"
#include "campaign/result_files.h"
#include "transport/clock.h"

namespace nimble::detection_power {
namespace {

namespace fs = std::filesystem;
/// Offset of the verification's campaign seed: its flights share no seed with the curve's.
constexpr std::uint64_t kVerifySeedOffset = 1000003;

std::string fmt_number(double x) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4g", x);
  return text;
}

// ---- one flight's outcome through the worker's pipe: tab-separated fields ----

std::string join(const std::vector<std::string>& v) {
  std::string out;
  for (const auto& s : v) out += (out.empty() ? "" : ",") + s;
  return out;
}

std::vector<std::string> split(const std::string& text, char sep) {
  std::vector<std::string> out;
  std::string item;
  std::istringstream in(text);
  while (std::getline(in, item, sep)) out.push_back(item);
  if (!text.empty() && text.back() == sep) out.emplace_back();
  return out;
}

std::string encode(const FlightOutcome& o) {
  std::string error = o.error;
  std::replace(error.begin(), error.end(), '\t', ' ');
  std::ostringstream s;
  s.precision(9);
  s << o.seed << '\t' << o.run_exit << '\t' << (o.analysed ? 1 : 0) << '\t' << o.verdict << '\t' << join(o.named)
    << '\t' << join(o.ambiguous) << '\t' << o.flight_s << '\t' << o.build_s << '\t' << o.workflow_s << '\t'
    << o.flight_cpu_s << '\t' << o.workflow_cpu_s << '\t' << error;
  return s.str();
}

FlightOutcome decode(const std::string& line) {
  FlightOutcome o;
  const std::vector<std::string> f = split(line, '\t');
  if (f.size() != 12) {
    o.error = line.rfind("error ", 0) == 0 ? line.substr(6) : "unreadable worker result: " + line;
    return o;
  }
  o.seed = std::stoull(f[0]);
  o.run_exit = std::stoi(f[1]);
  o.analysed = f[2] == "1";
  o.verdict = f[3];
  if (!f[4].empty()) o.named = split(f[4], ',');
  if (!f[5].empty()) o.ambiguous = split(f[5], ',');
  o.flight_s = std::stod(f[6]);
  o.build_s = std::stod(f[7]);
  o.workflow_s = std::stod(f[8]);
  o.flight_cpu_s = std::stod(f[9]);
  o.workflow_cpu_s = std::stod(f[10]);
  o.error = f[11];
  return o;
}

// ---- the cells ----

/// A cell to fly: its plan and its place.
struct CellPlan {
  double size = 0.0;
  RecordLength length;
  launcher::RunPlan plan;
};

CellPlan plan_cell(const PowerOptions& o, const YAML::Node& tree, const Scenario& scenario, double size,
                   double length_s, const std::string& dir) {
  CellPlan c;
  c.size = size;
  c.length = record_length(scenario, length_s, dir);
  launcher::RunOptions ro;
  ro.scenario_file = o.scenario_file;
  ro.overrides = o.overrides;
  for (const Override& v : size_overrides(tree, o.effect, size)) ro.overrides.push_back(v);
  for (const Override& v : c.length.overrides) ro.overrides.push_back(v);
  ro.clock = launcher::kClockInprocess;
  ro.progress = false;
  ro.print_summary = false;
  c.plan = launcher::load_run_plan(ro);
  return c;
}

/// A flight's key among a campaign directory's result files: its size, length and seed decide it.
std::string flight_key(double size, double length_s, std::uint64_t seed) {
  std::string key = "size" + shortest_text(size) + "_length" + shortest_text(length_s) + "_seed" + std::to_string(seed);
  for (char& ch : key) {
    if (ch == '+') ch = 'p';
  }
  return key;
}

/// Flies `flights` seeds of `campaign_seed` in every cell; fills the cells' flights. With
/// `files`, a flight that has a result there is read, not flown, and each one flown is kept.
void fly_cells(const std::vector<CellPlan>& plans, std::vector<PowerCell>& cells, int flights,
               std::uint64_t campaign_seed, const FlightCheck& check, int jobs, bool progress, const char* what,
               const campaign::ResultFiles* files) {
  const std::size_t n = plans.size() * static_cast<std::size_t>(flights);
  const bool tty = ::isatty(STDERR_FILENO);
  const std::int64_t start = transport::monotonic_ns();
  std::size_t last_shown = 0;
  const auto show = [&](std::size_t done) {
    if (!progress || (done < n && done - last_shown < std::max<std::size_t>(1, n / (tty ? 200 : 10)))) return;
    last_shown = done;
    std::fprintf(stderr, tty ? "\r[power] %s: %zu/%zu flights, %.1f s" : "[power] %s: %zu/%zu flights, %.1f s\n", what,
                 done, n, static_cast<double>(transport::monotonic_ns() - start) / 1e9);
    if (tty && done == n) std::fprintf(stderr, "\n");
  };
  campaign::PoolWork pool;
  pool.work = [&](std::size_t item) {
    const std::size_t c = item / static_cast<std::size_t>(flights), i = item % static_cast<std::size_t>(flights);
    return encode(fly_and_check(plans[c].plan, flight_seed(campaign_seed, i), check));
  };
  pool.died = [&](std::size_t item, const std::string& how) {
    FlightOutcome o;
    o.seed = flight_seed(campaign_seed, item % static_cast<std::size_t>(flights));
    o.error = "the worker flying it died (" + how + ")";
    return encode(o);
  };
  pool.finished = [&](std::size_t, const std::string&, std::size_t done) { show(done); };
  campaign::KeptItems kept;
  for (std::size_t item = 0; item < n; ++item) {
    const CellPlan& c = plans[item / static_cast<std::size_t>(flights)];
    kept.keys.push_back(
        flight_key(c.size, c.length.length_s, flight_seed(campaign_seed, item % static_cast<std::size_t>(flights))));
  }
  kept.keep = [](const std::string& line) { return decode(line).error.empty(); };
  const auto lines = campaign::run_kept(kept, jobs, pool, files);
  for (std::size_t item = 0; item < n; ++item) {
    cells[item / static_cast<std::size_t>(flights)].flights.push_back(decode(lines[item]));
  }
}

/// The counts of a cell from its flights.
void tally(PowerCell& c, const std::string& named_as) {
  int named = 0, other = 0, alarm = 0;
  for (const FlightOutcome& f : c.flights) {
    c.flight_s += f.flight_s;
    c.build_s += f.build_s;
    c.workflow_s += f.workflow_s;
    c.flight_cpu_s += f.flight_cpu_s;
    c.workflow_cpu_s += f.workflow_cpu_s;
    if (f.run_exit != launcher::kRunOk) ++c.not_ok;
    if (!f.analysed) {
      ++c.failed;
      continue;
    }
    bool hit = false, wrong = false;
    for (const auto& name : f.named) {
      if (name == named_as) {
        hit = true;
      } else {
        wrong = true;
        ++c.other_names[name];
      }
    }
    ++c.verdicts[f.verdict];
    named += hit;
    other += wrong;
    alarm += f.verdict != "none";
  }
  const int n = static_cast<int>(c.flights.size());
  c.named = wilson(named, n);
  c.other = wilson(other, n);
  c.alarm = wilson(alarm, n);
}

/// The manifest of a power campaign kept in a directory: what decides a flight's outcome besides
/// its size, length and seed (its key). The scenario as flown (scenario_digest of the plan with
/// --set: the file and all it names), the effect, the model and vehicle the workflow checks and
/// its candidates, and the rig's executable, by content.
campaign::Manifest power_manifest(const PowerOptions& o, const launcher::RunPlan& base, const FlightCheck& check) {
  nlohmann::json m;
  m["scenario_digest"] = scenario_digest(base.scenario);
  m["effect"] = o.effect;
  m["model_digest"] = file_digest(o.model_file);
  m["vehicle_digest"] = file_digest(check.vehicle.file);
  m["candidates"] = check.options.candidates;
  m["rig_digest"] = file_digest("/proc/self/exe", InputKind::kProgram);
  return campaign::Manifest{"rig discrepancy --power", m, {}};
}

/// A length rounded to 0.01 s (refined lengths: a record is flown at whole plant steps anyway).
double rounded_length(double length_s) { return std::max(0.01, std::round(length_s * 100.0) / 100.0); }

/// The campaign as it goes: what every round of cells needs.
class Campaign {
 public:
  Campaign(const PowerOptions& o, PowerResult& r, const launcher::RunPlan& base, const FlightCheck& check,
           std::string dir)
      : o_(o), r_(r), base_(base), check_(check), dir_(std::move(dir)) {}

  /// Flies one round: the cells (size, length), with `flights` seeds of `seed`; returns them.
  std::vector<PowerCell> fly(const std::vector<std::pair<double, double>>& which, const std::string& kind, int flights,
                             std::uint64_t seed) {
    std::vector<CellPlan> plans;
    std::vector<PowerCell> cells;
    for (const auto& [size, length] : which) {
      plans.push_back(plan_cell(o_, base_.scenario.root, base_.scenario, size, length, dir_));
      PowerCell c;
      c.size = size;
      c.length_s = length;
      c.repetitions = plans.back().length.repetitions;
      c.kind = kind;
      cells.push_back(c);
    }
    if (cells.empty()) return cells;
    fly_cells(plans, cells, flights, seed, check_, r_.jobs, o_.progress, kind.c_str(), files_ ? &*files_ : nullptr);
    for (PowerCell& c : cells) tally(c, r_.named_as);
    return cells;
  }

  /// The curve of size `s` against the length, from every cell of that size so far.
  void update_curve(std::size_t s) {
    SizeCurve& curve = r_.curves[s];
    curve.cells.clear();
    for (std::size_t i = 0; i < r_.cells.size(); ++i) {
      if (r_.cells[i].size == curve.size) curve.cells.push_back(i);
    }
    std::sort(curve.cells.begin(), curve.cells.end(),
              [&](std::size_t a, std::size_t b) { return r_.cells[a].length_s < r_.cells[b].length_s; });
    std::vector<double> x;
    std::vector<Proportion> p;
    for (const std::size_t i : curve.cells) {
      x.push_back(r_.cells[i].length_s);
      p.push_back(r_.cells[i].named);
    }
    curve.length = crossing(x, p, o_.target, true);
  }

  bool has_length(std::size_t s, double length_s) const {
    for (const std::size_t i : r_.curves[s].cells) {
      if (std::fabs(r_.cells[i].length_s - length_s) < 0.005) return true;
    }
    return false;
  }

  /// The next length to fly for size `s`, or 0 if its crossing needs none: the interpolated
  /// length, kept within the middle half of the bracket (in sqrt(length)) so that both ends
  /// move in turn (a secant from an end far below the target creeps toward it from one side).
  double refinement(std::size_t s) const {
    const Crossing& c = r_.curves[s].length;
    if (!c.bracketed) return 0.0;
    const double a0 = std::sqrt(c.lo_x), a1 = std::sqrt(c.hi_x), w = a1 - a0;
    const double a = std::clamp(std::sqrt(c.value), a0 + 0.25 * w, a1 - 0.25 * w);
    const double next = rounded_length(a * a);
    return has_length(s, next) || next <= c.lo_x || next >= c.hi_x ? 0.0 : next;
  }

 private:
  const PowerOptions& o_;
  PowerResult& r_;
  const launcher::RunPlan& base_;
  const FlightCheck& check_;
  std::string dir_;

 public:
  std::optional<campaign::ResultFiles> files_;  ///< the campaign directory, if the results are kept
};

/// The grid's lengths: the user's, or the scenario's block times 1, 2, 4.
std::vector<double> grid_lengths(const PowerOptions& o, double block_s) {
  std::vector<double> lengths = o.lengths_s;
  if (lengths.empty()) lengths = {block_s, 2 * block_s, 4 * block_s};
  for (const double l : lengths) {
    if (!(std::isfinite(l) && l > 0.0))
      throw std::invalid_argument("record length " + fmt_number(l) + " s: must be > 0");
  }
  std::sort(lengths.begin(), lengths.end());
  lengths.erase(std::unique(lengths.begin(), lengths.end()), lengths.end());
  return lengths;
}

}  // namespace

PowerResult run_power(const PowerOptions& o) {
  if (o.flights < 1) throw std::invalid_argument("flights must be >= 1");
  if (o.sizes.empty()) throw std::invalid_argument("no effect size");
  const SizedEffect& effect = sized_effect(o.effect);
  const std::int64_t setup_start = transport::monotonic_ns();
  PowerResult r;
  r.effect = effect.effect;
  r.parameter = effect.parameter;
  r.unit = effect.unit;
  r.named_as = effect.named_as;
  r.target = o.target;
  r.flights = o.flights;
  r.seed = o.seed;
  r.jobs = std::max(1, o.jobs);
  r.sizes = o.sizes;
  for (const double size : r.sizes) {
    if (!effect.range.contains(size)) {
      throw std::invalid_argument("effect " + effect.effect + ": SIZE " + fmt_number(size) + " is not " +
                                  effect.range.describe());
    }
  }

  launcher::RunOptions base_options;
  base_options.scenario_file = o.scenario_file;
  base_options.overrides = o.overrides;
  base_options.clock = launcher::kClockInprocess;
  const launcher::RunPlan base = launcher::load_run_plan(base_options);
  r.scenario = base.scenario.name;
  r.block_s = block_length_s(base.scenario);
  r.lengths_s = grid_lengths(o, r.block_s);

  FlightCheck check;
  check.model = load_model(o.model_file);
  check.vehicle = load_vehicle(o.vehicle_file.empty() ? check.model.vehicle_file : o.vehicle_file);
  check.options = o.discrepancy;
  r.model = check.model.name;

  const fs::path dir = fs::temp_directory_path() / ("rig_power_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  struct Cleanup {
    fs::path dir;
    ~Cleanup() {
      std::error_code ec;
      fs::remove_all(dir, ec);
    }
  } cleanup{dir};
  Campaign campaign(o, r, base, check, dir.string());
  if (!o.result_dir.empty()) campaign.files_ = campaign::open_result_dir(o.result_dir, power_manifest(o, base, check));
  // Every plan of the grid loads before anything flies: a size the plant refuses stops it here.
  std::vector<std::pair<double, double>> grid;
  for (const double size : r.sizes) {
    for (const double length : r.lengths_s) {
      grid.emplace_back(size, length);
      plan_cell(o, base.scenario.root, base.scenario, size, length, dir.string());
    }
  }
  r.setup_s = static_cast<double>(transport::monotonic_ns() - setup_start) / 1e9;

  const std::int64_t start = transport::monotonic_ns();
  r.cells = campaign.fly(grid, "grid", o.flights, o.seed);
  for (const double size : r.sizes) r.curves.push_back(SizeCurve{size, {}, {}});
  for (std::size_t s = 0; s < r.sizes.size(); ++s) campaign.update_curve(s);

  // Longer records for the sizes that have not reached the target (default lengths only).
  const double longest = 16 * r.block_s;
  for (double length = 2 * r.lengths_s.back(); o.lengths_s.empty() && length <= longest + 1e-9; length *= 2) {
    std::vector<std::pair<double, double>> more;
    for (std::size_t s = 0; s < r.sizes.size(); ++s) {
      if (r.sizes[s] != 0.0 && !r.curves[s].length.reached) more.emplace_back(r.sizes[s], length);
    }
    if (more.empty()) break;
    for (PowerCell& c : campaign.fly(more, "longer", o.flights, o.seed)) r.cells.push_back(std::move(c));
    for (std::size_t s = 0; s < r.sizes.size(); ++s) campaign.update_curve(s);
  }
  for (int round = 0; round < o.refine; ++round) {
    std::vector<std::pair<double, double>> more;
    for (std::size_t s = 0; s < r.sizes.size(); ++s) {
      const double next = campaign.refinement(s);
      if (next > 0.0) more.emplace_back(r.sizes[s], next);
    }
    if (more.empty()) break;
    for (PowerCell& c : campaign.fly(more, "refined", o.flights, o.seed)) r.cells.push_back(std::move(c));
    for (std::size_t s = 0; s < r.sizes.size(); ++s) campaign.update_curve(s);
  }

  std::vector<std::size_t> order(r.sizes.size());
  for (std::size_t s = 0; s < order.size(); ++s) order[s] = s;
  std::sort(order.begin(), order.end(),
            [&](std::size_t a, std::size_t b) { return std::fabs(r.sizes[a]) < std::fabs(r.sizes[b]); });
  for (std::size_t l = 0; l < r.lengths_s.size(); ++l) {
    std::vector<double> x;
    std::vector<Proportion> along;
    for (const std::size_t s : order) {
      x.push_back(r.sizes[s]);
      along.push_back(r.cell(s, l).named);
    }
    r.size_for_length.push_back(crossing(x, along, o.target, false));
  }

  if (o.verify > 0) {
    std::vector<std::pair<double, double>> at;
    for (const SizeCurve& c : r.curves) {
      if (c.length.reached && c.size != 0.0) at.emplace_back(c.size, rounded_length(c.length.value));
    }
    r.verification = campaign.fly(at, "verification", o.verify, o.seed + kVerifySeedOffset);
  }
  r.wall_s = static_cast<double>(transport::monotonic_ns() - start) / 1e9;
  return r;
}

}  // namespace nimble::detection_power
