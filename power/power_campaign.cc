#include "power/power_campaign.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "power/effect_size.h"
#include "power/record_length.h"
#include "power/worker_pool.h"
#include "transport/clock.h"

namespace nimble::power {
namespace {

namespace fs = std::filesystem;
constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();
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

/// Flies `flights` seeds of `campaign_seed` in every cell; fills the cells' flights.
void fly_cells(const std::vector<CellPlan>& plans, std::vector<PowerCell>& cells, int flights,
               std::uint64_t campaign_seed, const FlightCheck& check, int jobs, bool progress, const char* what) {
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
  const auto lines = run_in_workers(
      n, jobs,
      [&](std::size_t item) {
        const std::size_t c = item / static_cast<std::size_t>(flights), i = item % static_cast<std::size_t>(flights);
        return encode(fly_and_check(plans[c].plan, flight_seed(campaign_seed, i), check));
      },
      [&](std::size_t item, const std::string& how) {
        FlightOutcome o;
        o.seed = flight_seed(campaign_seed, item % static_cast<std::size_t>(flights));
        o.error = "the worker flying it died (" + how + ")";
        return encode(o);
      },
      show);
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
    named += hit;
    other += wrong;
    alarm += f.verdict != "none";
  }
  const int n = static_cast<int>(c.flights.size());
  c.named = wilson(named, n);
  c.other = wilson(other, n);
  c.alarm = wilson(alarm, n);
}

}  // namespace

Proportion wilson(int count, int n, double z) {
  Proportion p;
  p.count = count;
  p.n = n;
  if (n <= 0) return p;
  const double nn = n, ph = count / nn, z2 = z * z;
  const double centre = (ph + z2 / (2 * nn)) / (1 + z2 / nn);
  const double half = z / (1 + z2 / nn) * std::sqrt(ph * (1 - ph) / nn + z2 / (4 * nn * nn));
  p.p = ph;
  p.lo = std::max(0.0, centre - half);
  p.hi = std::min(1.0, centre + half);
  return p;
}

Recommendation crossing(const std::vector<double>& x, const std::vector<Proportion>& props, double target,
                        bool sqrt_x) {
  Recommendation r;
  r.value = kNaN;
  const std::size_t m = x.size();
  if (m == 0) {
    r.note = "nothing flown";
    return r;
  }
  // Pool adjacent violators: the non-decreasing fit of the estimates, weighted by flights.
  std::vector<double> level, weight;
  std::vector<std::size_t> width;
  for (std::size_t i = 0; i < m; ++i) {
    level.push_back(props[i].p);
    weight.push_back(std::max(1, props[i].n));
    width.push_back(1);
    while (level.size() > 1 && level[level.size() - 2] > level.back()) {
      const std::size_t k = level.size() - 1;
      level[k - 1] = (level[k - 1] * weight[k - 1] + level[k] * weight[k]) / (weight[k - 1] + weight[k]);
      weight[k - 1] += weight[k];
      width[k - 1] += width[k];
      level.pop_back();
      weight.pop_back();
      width.pop_back();
    }
  }
  std::vector<double> p;
  for (std::size_t b = 0; b < level.size(); ++b) p.insert(p.end(), width[b], level[b]);
  const auto axis = [sqrt_x](double v) { return sqrt_x ? std::sqrt(std::fabs(v)) : std::fabs(v); };
  const auto probit = [](double q, int n) {
    const double e = 0.5 / std::max(1, n);
    q = std::clamp(q, e, 1.0 - e);
    // Phi^-1 by Newton on erfc, from a logistic start: ample for a probability of 0.5/n .. 1 - 0.5/n.
    double z = std::log(q / (1 - q)) / 1.7;
    for (int it = 0; it < 50; ++it) {
      const double f = 0.5 * std::erfc(-z / std::sqrt(2.0)) - q;
      const double d = std::exp(-0.5 * z * z) / 2.5066282746310002;
      z -= f / d;
    }
    return z;
  };
  if (p[0] >= target) {
    r.reached = true;
    r.value = x[0];
    r.note = "at or below " + fmt_number(x[0]) + ", the first value flown";
    return r;
  }
  for (std::size_t i = 1; i < m; ++i) {
    if (p[i] < target) continue;
    const int n = std::max(props[i - 1].n, props[i].n);
    const double z0 = probit(p[i - 1], n), z1 = probit(p[i], n), zt = probit(target, 1 << 30);
    const double a0 = axis(x[i - 1]), a1 = axis(x[i]);
    const double f = z1 > z0 ? std::clamp((zt - z0) / (z1 - z0), 0.0, 1.0) : 1.0;
    const double a = a0 + f * (a1 - a0);
    r.reached = true;
    r.value = (sqrt_x ? a * a : a) * (x[i] < 0 ? -1.0 : 1.0);
    r.note = "interpolated between " + fmt_number(x[i - 1]) + " and " + fmt_number(x[i]);
    return r;
  }
  r.note = "not reached by " + fmt_number(x[m - 1]) + " (there " + fmt_number(100 * p[m - 1]) + " %)";
  return r;
}

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

  launcher::RunOptions base;
  base.scenario_file = o.scenario_file;
  base.overrides = o.overrides;
  base.clock = launcher::kClockInprocess;
  const launcher::RunPlan base_plan = launcher::load_run_plan(base);
  r.scenario = base_plan.scenario.name;
  r.block_s = block_length_s(base_plan.scenario);
  r.lengths_s = o.lengths_s;
  if (r.lengths_s.empty()) {
    for (const double k : {1.0, 2.0, 4.0, 8.0}) r.lengths_s.push_back(k * r.block_s);
  }
  for (const double l : r.lengths_s) {
    if (!(std::isfinite(l) && l > 0.0)) throw std::invalid_argument("record length " + fmt_number(l) + " s: must be > 0");
  }
  std::sort(r.lengths_s.begin(), r.lengths_s.end());
  r.lengths_s.erase(std::unique(r.lengths_s.begin(), r.lengths_s.end()), r.lengths_s.end());

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

  std::vector<CellPlan> plans;
  for (const double size : r.sizes) {
    for (const double length : r.lengths_s) {
      plans.push_back(plan_cell(o, base_plan.scenario.root, base_plan.scenario, size, length, dir.string()));
      PowerCell c;
      c.size = size;
      c.length_s = length;
      c.repetitions = plans.back().length.repetitions;
      r.cells.push_back(c);
    }
  }
  r.setup_s = static_cast<double>(transport::monotonic_ns() - setup_start) / 1e9;

  const std::int64_t start = transport::monotonic_ns();
  fly_cells(plans, r.cells, o.flights, o.seed, check, r.jobs, o.progress, "curve");
  for (PowerCell& c : r.cells) tally(c, r.named_as);

  for (std::size_t s = 0; s < r.sizes.size(); ++s) {
    std::vector<Proportion> along;
    for (std::size_t l = 0; l < r.lengths_s.size(); ++l) along.push_back(r.cell(s, l).named);
    r.length_for_size.push_back(crossing(r.lengths_s, along, o.target, true));
  }
  std::vector<std::size_t> order(r.sizes.size());
  for (std::size_t s = 0; s < order.size(); ++s) order[s] = s;
  std::sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) {
    return std::fabs(r.sizes[a]) < std::fabs(r.sizes[b]);
  });
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
    std::vector<CellPlan> vplans;
    std::vector<PowerCell> vcells;
    for (std::size_t s = 0; s < r.sizes.size(); ++s) {
      const Recommendation& rec = r.length_for_size[s];
      if (!rec.reached || r.sizes[s] == 0.0) continue;
      vplans.push_back(plan_cell(o, base_plan.scenario.root, base_plan.scenario, r.sizes[s], rec.value, dir.string()));
      PowerCell c;
      c.size = r.sizes[s];
      c.length_s = rec.value;
      c.repetitions = vplans.back().length.repetitions;
      vcells.push_back(c);
    }
    fly_cells(vplans, vcells, o.verify, o.seed + kVerifySeedOffset, check, r.jobs, o.progress, "verification");
    for (PowerCell& c : vcells) tally(c, r.named_as);
    r.verification = vcells;
  }
  r.wall_s = static_cast<double>(transport::monotonic_ns() - start) / 1e9;
  return r;
}

}  // namespace nimble::power
