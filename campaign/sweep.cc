#include "campaign/sweep.h"

#include "campaign/campaign.h"
#include "core/json_line.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <sstream>
#include <stdexcept>

namespace nimble::campaign {

// One run is the launcher's (run plan, executors, report); a campaign flies many.
using namespace launcher;
namespace {

/// The percentiles the summary and the JSON give, and their JSON names.
constexpr double kPercentiles[] = {0.0, 5.0, 50.0, 95.0, 100.0};

/// One parameter set's runs and what both the summary and the JSON say of them.
struct SetStatistics {
  std::vector<const SweepRun*> runs;
  long long controlled = 0, hover = 0, ok = 0;
  std::map<std::string, std::vector<double>> by_figure;  ///< figure key -> its value in each run that has it
};

SetStatistics set_statistics(const SweepResult& r, std::size_t set) {
  SetStatistics st;
  for (const auto& run : r.runs) {
    if (run.set != set) continue;
    st.runs.push_back(&run);
    st.controlled += run.controlled;
    st.hover += run.hover;
    st.ok += run.exit_code == kRunOk;
    for (const auto& [k, v] : run.figures) st.by_figure[k].push_back(v);
  }
  return st;
}

}  // namespace

Vary parse_vary(const std::string& text) {
  const auto eq = text.find('=');
  if (eq == std::string::npos || eq == 0 || eq + 1 >= text.size()) {
    throw std::invalid_argument("--vary needs key=value1,value2,..., got '" + text + "'");
  }
  Vary v;
  v.key = trim(text.substr(0, eq));
  int depth = 0;
  std::string current;
  for (const char c : text.substr(eq + 1)) {
    if (c == '[' || c == '{') ++depth;
    if (c == ']' || c == '}') --depth;
    if (c == ',' && depth == 0) {
      v.values.push_back(trim(current));
      current.clear();
    } else {
      current += c;
    }
  }
  v.values.push_back(trim(current));
  for (const auto& value : v.values) {
    if (value.empty()) throw std::invalid_argument("--vary " + v.key + ": an empty value in '" + text + "'");
  }
  if (depth != 0) throw std::invalid_argument("--vary " + v.key + ": unbalanced brackets in '" + text + "'");
  return v;
}

std::pair<uint64_t, uint64_t> parse_seed_range(const std::string& text) {
  const auto bad = [&] {
    return std::invalid_argument("--seeds needs A-B or A (whole numbers, A <= B), got '" + text + "'");
  };
  const auto number = [&](const std::string& s) {
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos) throw bad();
    try {
      return static_cast<uint64_t>(std::stoull(s));
    } catch (const std::exception&) {
      throw bad();
    }
  };
  const auto dash = text.find('-');
  if (dash == std::string::npos) {
    const uint64_t a = number(text);
    return {a, a};
  }
  const uint64_t a = number(text.substr(0, dash)), b = number(text.substr(dash + 1));
  if (a > b) throw bad();
  return {a, b};
}

std::vector<ParameterSet> parameter_sets(const std::vector<Vary>& vary) {
  std::vector<ParameterSet> sets(1);
  for (const Vary& v : vary) {
    std::vector<ParameterSet> next;
    for (const ParameterSet& s : sets) {
      for (const std::string& value : v.values) {
        ParameterSet n = s;
        n.label += (n.label.empty() ? "" : " ") + v.key + "=" + value;
        n.overrides.push_back(Override{v.key, value});
        next.push_back(std::move(n));
      }
    }
    sets = std::move(next);
  }
  if (vary.empty()) sets[0].label = "scenario as given";
  return sets;
}

const std::vector<SweepFigure>& sweep_figures() {
  static const std::vector<SweepFigure> figures = {
      {"max_abs_phi_deg", "max |phi| [deg]"},
      {"max_abs_p", "max |p| [rad/s]"},
      {"max_abs_v", "max |v| [m/s]"},
      {"range_p", "range p [rad/s]"},
      {"range_v", "range v [m/s]"},
      {"range_phi", "range phi [rad]"},
      {"range_delta_f", "range delta_f [rad/s]"},
      {"final_abs_phi_deg", "final |phi| [deg]"},
      {"est_phi_rms_deg", "estimator phi error rms [deg]"},
      {"est_p_rms", "estimator p error rms [rad/s]"},
      {"est_v_rms", "estimator v error rms [m/s]"},
  };
  return figures;
}

double percentile(std::vector<double> values, double pct) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double pos = std::clamp(pct, 0.0, 100.0) / 100.0 * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(pos));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  return values[lo] + (pos - static_cast<double>(lo)) * (values[hi] - values[lo]);
}

void write_sweep_text(std::ostream& out, const SweepResult& r) {
  const std::size_t seeds = r.sets.empty() ? 0 : r.runs.size() / r.sets.size();
  char line[256];
  out << "\n== sweep: " << r.scenario << " ==\n";
  std::snprintf(line, sizeof line,
                "%zu runs: %zu parameter set%s x %zu seed%s (%llu-%llu), clock %s, %d job%s, %.2f s\n", r.runs.size(),
                r.sets.size(), r.sets.size() == 1 ? "" : "s", seeds, seeds == 1 ? "" : "s",
                r.runs.empty() ? 0ULL : static_cast<unsigned long long>(r.runs.front().seed),
                r.runs.empty() ? 0ULL : static_cast<unsigned long long>(r.runs.back().seed), r.clock.c_str(), r.jobs,
                r.jobs == 1 ? "" : "s", r.wall_time_s);
  out << line;
  std::vector<double> speeds;
  for (const auto& run : r.runs) {
    if (run.speed_x_realtime > 0) speeds.push_back(run.speed_x_realtime);
  }
  if (r.backend != "local") {
    std::snprintf(line, sizeof line, "backend %s, %zu runs per task, %d CPU%s per task\n", r.backend.c_str(),
                  r.chunk_size, r.jobs, r.jobs == 1 ? "" : "s");
    out << line;
  }
  if (!speeds.empty()) {
    std::snprintf(line, sizeof line, "each run %.4g x real time (median of the runs)\n", percentile(speeds, 50));
    out << line;
  }
  for (std::size_t s = 0; s < r.sets.size(); ++s) {
    const SetStatistics st = set_statistics(r, s);
    const long long n = static_cast<long long>(st.runs.size());
    std::snprintf(line, sizeof line,
                  "\n[%zu] %s\n    controlled %lld/%lld (%.0f %%), back to hover %lld/%lld, result ok %lld/%lld\n",
                  s + 1, r.sets[s].label.c_str(), st.controlled, n,
                  n == 0 ? 0.0 : 100.0 * static_cast<double>(st.controlled) / static_cast<double>(n), st.hover, n,
                  st.ok, n);
    out << line;
    std::snprintf(line, sizeof line, "    %-32s %10s %10s %10s %10s %10s\n", "across runs", "min", "p5", "p50", "p95",
                  "max");
    out << line;
    for (const auto& fig : sweep_figures()) {
      const auto it = st.by_figure.find(fig.key);
      if (it == st.by_figure.end()) continue;
      std::snprintf(line, sizeof line, "    %-32s", fig.label);
      out << line;
      for (const double p : kPercentiles) {
        std::snprintf(line, sizeof line, " %10.4g", percentile(it->second, p));
        out << line;
      }
      out << "\n";
    }
    for (const auto* run : st.runs) {
      if (run->exit_code == kRunOk) continue;
      out << "    seed " << run->seed << ": " << run->verdict << "\n";
    }
  }
}

std::string sweep_json(const SweepResult& r) {
  OrderedJson j = {{"scenario", r.scenario}, {"clock", r.clock}, {"sets", OrderedJson::array()}};
  for (std::size_t s = 0; s < r.sets.size(); ++s) {
    OrderedJson overrides = OrderedJson::object();
    for (const auto& ov : r.sets[s].overrides) overrides[ov.key_path] = ov.value;
    const SetStatistics st = set_statistics(r, s);
    const std::size_t n = st.runs.size();
    OrderedJson percentiles = OrderedJson::object();
    for (const auto& fig : sweep_figures()) {
      const auto it = st.by_figure.find(fig.key);
      if (it == st.by_figure.end()) continue;
      OrderedJson& at = percentiles[fig.key];
      at = OrderedJson::object();
      for (const double p : kPercentiles) at["p" + std::to_string(static_cast<int>(p))] = percentile(it->second, p);
    }
    j["sets"].push_back({{"label", r.sets[s].label},
                         {"overrides", std::move(overrides)},
                         {"runs", n},
                         {"controlled", st.controlled},
                         {"returned_to_hover", st.hover},
                         {"ok", st.ok},
                         {"controlled_rate", n > 0 ? static_cast<double>(st.controlled) / static_cast<double>(n) : 0.0},
                         {"percentiles", std::move(percentiles)}});
  }
  j["runs"] = OrderedJson::array();
  for (const auto& run : r.runs) {
    OrderedJson figures = OrderedJson::object();
    for (const auto& [k, v] : run.figures) figures[k] = v;
    j["runs"].push_back(
        {{"set", run.set + 1},
         {"seed", run.seed},
         {"exit_code", run.exit_code},
         {"result", run.verdict},
         {"controlled", run.controlled},
         {"returned_to_hover", run.hover},
         {"sim_time_s", run.sim_time_s},
         {"figures", std::move(figures)},
         {"machine",
          {{"host", run.host}, {"wall_time_s", run.wall_time_s}, {"speed_x_realtime", run.speed_x_realtime}}}});
  }
  j["machine"] = {
      {"backend", r.backend}, {"jobs", r.jobs}, {"chunk_size", r.chunk_size}, {"wall_time_s", r.wall_time_s}};
  return json_line(j);
}

std::string sweep_csv(const SweepResult& r) {
  std::ostringstream out;
  out.precision(10);
  out << "set,label,seed,exit_code,result,controlled,returned_to_hover,sim_time_s";
  for (const auto& fig : sweep_figures()) out << "," << fig.key;
  out << ",machine_host,machine_wall_time_s,machine_speed_x_realtime\n";
  const auto quoted = [](const std::string& s) {
    std::string q = "\"";
    for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  for (const auto& run : r.runs) {
    out << run.set + 1 << "," << quoted(r.sets[run.set].label) << "," << run.seed << "," << run.exit_code << ","
        << quoted(run.verdict) << "," << run.controlled << "," << run.hover << "," << run.sim_time_s;
    for (const auto& fig : sweep_figures()) {
      const auto it = run.figures.find(fig.key);
      out << ",";
      if (it != run.figures.end()) out << it->second;
    }
    out << "," << quoted(run.host) << "," << run.wall_time_s << "," << run.speed_x_realtime << "\n";
  }
  return out.str();
}

}  // namespace nimble::campaign
