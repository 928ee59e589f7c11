#include "launcher/sweep.h"

#include <fcntl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include <yaml-cpp/yaml.h>

#include "core/json_writer.h"
#include "launcher/inprocess.h"
#include "transport/clock.h"

namespace nimble::launcher {
namespace {

namespace fs = std::filesystem;

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t") - a + 1);
}

std::string self_exe() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("rig") : exe.string();
}

/// A file-name-safe tag of a parameter set and seed.
std::string run_tag(std::size_t set, uint64_t seed) {
  return "set" + std::to_string(set + 1) + "-seed" + std::to_string(seed);
}

double number_or_nan(const YAML::Node& n) {
  if (!n || !n.IsScalar()) return std::numeric_limits<double>::quiet_NaN();
  try {
    return n.as<double>();
  } catch (const YAML::Exception&) {
    return std::numeric_limits<double>::quiet_NaN();
  }
}

/// The figures of a run from its `rig run --json` report.
void read_report(const YAML::Node& j, SweepRun& run) {
  constexpr double kDeg = 180.0 / M_PI;
  run.exit_code = j["exit_code"].as<int>();
  run.verdict = j["result"].as<std::string>();
  run.controlled = j["controlled"].as<bool>();
  run.hover = j["returned_to_hover"].as<bool>();
  run.sim_time_s = number_or_nan(j["sim_time_s"]);
  run.wall_time_s = number_or_nan(j["wall_time_s"]);
  auto& f = run.figures;
  f["max_abs_phi_deg"] = number_or_nan(j["max_abs"]["phi"]) * kDeg;
  f["max_abs_p"] = number_or_nan(j["max_abs"]["p"]);
  f["max_abs_v"] = number_or_nan(j["max_abs"]["v"]);
  f["range_p"] = number_or_nan(j["ranges"]["p"]);
  f["range_v"] = number_or_nan(j["ranges"]["v"]);
  f["range_phi"] = number_or_nan(j["ranges"]["phi"]);
  f["range_delta_f"] = number_or_nan(j["ranges"]["delta_f"]);
  f["final_abs_phi_deg"] = std::fabs(number_or_nan(j["final"]["phi"])) * kDeg;
  if (j["estimator"]) {
    f["est_phi_rms_deg"] = number_or_nan(j["estimator"]["phi_rms_deg"]);
    f["est_p_rms"] = number_or_nan(j["estimator"]["p_rms_radps"]);
    f["est_v_rms"] = number_or_nan(j["estimator"]["v_rms_mps"]);
  }
  f["speed_x_realtime"] = number_or_nan(j["speed_x_realtime"]);
  for (auto it = f.begin(); it != f.end();) it = std::isfinite(it->second) ? std::next(it) : f.erase(it);
}

/// The options of one run.
RunOptions run_options(const SweepOptions& o, const ParameterSet& set, uint64_t seed) {
  RunOptions r = o.base;
  r.overrides.insert(r.overrides.end(), set.overrides.begin(), set.overrides.end());
  r.seed = seed;
  r.progress = false;
  r.print_summary = false;
  return r;
}

/// In a child process: flies one run and writes its report to `json_file`. Never returns.
[[noreturn]] void fly_child(const RunOptions& options, const std::string& json_file, const std::string& log_file,
                            const std::string& out_file) {
  const int fd = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
  if (fd >= 0) {
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    ::close(fd);
  }
  int code = kRunFailed;
  try {
    const RunPlan plan = load_run_plan(options);
    if (plan.inprocess()) {
      InprocessOptions io;
      io.log_file = log_file;
      const RunReport report = fly_inprocess(plan, io);
      std::ofstream out(json_file);
      out << report_json(report) << "\n";
      code = out ? report.verdict.exit_code : kRunFailed;
    } else {
      // Another clock: `rig run` itself, which makes its own network namespace.
      std::vector<std::string> args = {self_exe(), "run", options.scenario_file, "--clock", *options.clock,
                                       "--seed", std::to_string(*options.seed), "--json", json_file,
                                       "--log", log_file.empty() ? json_file + ".lcmlog" : log_file, "--no-progress"};
      for (const auto& ov : options.overrides) {
        args.push_back("--set");
        args.push_back(ov.key_path + "=" + ov.value);
      }
      std::vector<char*> argv;
      for (auto& a : args) argv.push_back(a.data());
      argv.push_back(nullptr);
      ::execv(argv[0], argv.data());
      std::fprintf(stderr, "cannot execute %s: %s\n", argv[0], std::strerror(errno));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
  }
  std::fflush(stdout);
  std::fflush(stderr);
  ::_exit(code);
}

std::string last_line(const std::string& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!trim(line).empty()) last = trim(line);
  }
  return last;
}

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

void progress_bar(std::size_t done, std::size_t total, std::size_t failed, double wall_s, bool tty) {
  // Not a terminal: a line at every tenth of the campaign, not one per run.
  if (!tty && done != total && (done * 10 / std::max<std::size_t>(total, 1)) ==
                                   ((done - (done > 0)) * 10 / std::max<std::size_t>(total, 1)) && done > 0) {
    return;
  }
  constexpr int kWidth = 30;
  const int filled = total > 0 ? static_cast<int>(kWidth * done / total) : kWidth;
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(kWidth, '-');
  std::fprintf(stderr, "%s[%s] %zu/%zu runs, %zu not ok, %.1f s%s", tty ? "\r" : "", bar.c_str(), done, total,
               failed, wall_s, tty ? "" : "\n");
  if (tty && done == total) std::fprintf(stderr, "\n");
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
  const auto bad = [&] { return std::invalid_argument("--seeds needs A-B or A (whole numbers, A <= B), got '" + text + "'"); };
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
      {"speed_x_realtime", "speed [x real time]"},
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

SweepResult run_sweep(const SweepOptions& options) {
  SweepResult result;
  result.clock = options.base.clock.value_or(kClockInprocess);
  result.sets = parameter_sets(options.vary);
  result.jobs = std::max(1, options.jobs);
  SweepOptions o = options;
  o.base.clock = result.clock;

  // Every set's plan is loaded before anything flies: a bad value stops the sweep at once.
  for (const ParameterSet& set : result.sets) {
    try {
      const RunPlan plan = load_run_plan(run_options(o, set, o.first_seed));
      result.scenario = plan.scenario.name;
    } catch (const ConfigError& e) {
      throw ConfigError(e.file(), e.key(), e.value(), e.problem() + " (in parameter set '" + set.label + "')", e.line());
    }
  }
  for (std::size_t s = 0; s < result.sets.size(); ++s) {
    for (uint64_t seed = o.first_seed; seed <= o.last_seed; ++seed) {
      SweepRun r;
      r.set = s;
      r.seed = seed;
      result.runs.push_back(r);
      if (seed == std::numeric_limits<uint64_t>::max()) break;
    }
  }

  const fs::path work = fs::temp_directory_path() / ("rig_sweep_" + std::to_string(::getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  if (!o.logs_dir.empty()) fs::create_directories(o.logs_dir);

  const bool tty = ::isatty(STDERR_FILENO);
  const int64_t start_ns = transport::monotonic_ns();
  std::map<pid_t, std::size_t> running;
  std::size_t next = 0, done = 0, failed = 0;
  const auto files = [&](std::size_t i) {
    const std::string tag = run_tag(result.runs[i].set, result.runs[i].seed);
    return std::array<std::string, 3>{(work / (tag + ".json")).string(), (work / (tag + ".out")).string(),
                                      o.logs_dir.empty() ? std::string() : (fs::path(o.logs_dir) / (tag + ".lcmlog")).string()};
  };
  if (o.progress) progress_bar(0, result.runs.size(), 0, 0.0, tty);
  while (done < result.runs.size()) {
    while (next < result.runs.size() && static_cast<int>(running.size()) < result.jobs) {
      const auto [json, out, log] = files(next);
      const SweepRun& r = result.runs[next];
      const RunOptions ro = run_options(o, result.sets[r.set], r.seed);
      std::fflush(stdout);
      std::fflush(stderr);
      const pid_t pid = ::fork();
      if (pid == 0) fly_child(ro, json, log, out);
      if (pid < 0) throw std::runtime_error(std::string("rig sweep: fork failed: ") + std::strerror(errno));
      running[pid] = next++;
    }
    int status = 0;
    const pid_t pid = ::waitpid(-1, &status, 0);
    if (pid < 0) {
      if (errno == EINTR) continue;
      throw std::runtime_error(std::string("rig sweep: waitpid failed: ") + std::strerror(errno));
    }
    const auto it = running.find(pid);
    if (it == running.end()) continue;
    const std::size_t i = it->second;
    running.erase(it);
    SweepRun& r = result.runs[i];
    const auto [json, out, log] = files(i);
    try {
      if (!fs::exists(json)) throw std::runtime_error("no report");
      read_report(YAML::LoadFile(json), r);
    } catch (const std::exception&) {
      r.exit_code = kRunFailed;
      const std::string how = WIFSIGNALED(status) ? "killed by signal " + std::to_string(WTERMSIG(status))
                                                   : "exit code " + std::to_string(WEXITSTATUS(status));
      const std::string said = last_line(out);
      r.verdict = "failed: the run ended without a report (" + how + ")" + (said.empty() ? "" : ": " + said);
    }
    ++done;
    if (r.exit_code != kRunOk) ++failed;
    if (o.progress) {
      progress_bar(done, result.runs.size(), failed,
                   static_cast<double>(transport::monotonic_ns() - start_ns) / 1e9, tty);
    }
  }
  result.wall_time_s = static_cast<double>(transport::monotonic_ns() - start_ns) / 1e9;
  std::error_code ec;
  fs::remove_all(work, ec);
  return result;
}

void write_sweep_text(std::ostream& out, const SweepResult& r) {
  const std::size_t seeds = r.sets.empty() ? 0 : r.runs.size() / r.sets.size();
  char line[256];
  out << "\n== sweep: " << r.scenario << " ==\n";
  std::snprintf(line, sizeof line, "%zu runs: %zu parameter set%s x %zu seed%s (%llu-%llu), clock %s, %d job%s, %.2f s\n",
                r.runs.size(), r.sets.size(), r.sets.size() == 1 ? "" : "s", seeds, seeds == 1 ? "" : "s",
                r.runs.empty() ? 0ULL : static_cast<unsigned long long>(r.runs.front().seed),
                r.runs.empty() ? 0ULL : static_cast<unsigned long long>(r.runs.back().seed), r.clock.c_str(), r.jobs,
                r.jobs == 1 ? "" : "s", r.wall_time_s);
  out << line;
  for (std::size_t s = 0; s < r.sets.size(); ++s) {
    const SetStatistics st = set_statistics(r, s);
    const long long n = static_cast<long long>(st.runs.size());
    std::snprintf(line, sizeof line, "\n[%zu] %s\n    controlled %lld/%lld (%.0f %%), back to hover %lld/%lld, result ok %lld/%lld\n",
                  s + 1, r.sets[s].label.c_str(), st.controlled, n,
                  n == 0 ? 0.0 : 100.0 * static_cast<double>(st.controlled) / static_cast<double>(n), st.hover, n, st.ok,
                  n);
    out << line;
    std::snprintf(line, sizeof line, "    %-32s %10s %10s %10s %10s %10s\n", "across runs", "min", "p5", "p50", "p95", "max");
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
  JsonWriter w;
  w.begin_object();
  w.key("scenario").value(r.scenario);
  w.key("clock").value(r.clock);
  w.key("jobs").value(r.jobs);
  w.key("wall_time_s").value(r.wall_time_s);
  w.key("sets").begin_array();
  for (std::size_t s = 0; s < r.sets.size(); ++s) {
    w.begin_object();
    w.key("label").value(r.sets[s].label);
    w.key("overrides").begin_object();
    for (const auto& ov : r.sets[s].overrides) w.key(ov.key_path).value(ov.value);
    w.end_object();
    const SetStatistics st = set_statistics(r, s);
    const long long n = static_cast<long long>(st.runs.size());
    w.key("runs").value(n).key("controlled").value(st.controlled).key("returned_to_hover").value(st.hover);
    w.key("ok").value(st.ok);
    w.key("controlled_rate").value(n > 0 ? static_cast<double>(st.controlled) / static_cast<double>(n) : 0.0);
    w.key("percentiles").begin_object();
    for (const auto& fig : sweep_figures()) {
      const auto it = st.by_figure.find(fig.key);
      if (it == st.by_figure.end()) continue;
      w.key(fig.key).begin_object();
      for (const double p : kPercentiles) {
        w.key("p" + std::to_string(static_cast<int>(p))).value(percentile(it->second, p));
      }
      w.end_object();
    }
    w.end_object();
    w.end_object();
  }
  w.end_array();
  w.key("runs").begin_array();
  for (const auto& run : r.runs) {
    w.begin_object();
    w.key("set").value(static_cast<long long>(run.set + 1));
    w.key("seed").value(static_cast<long long>(run.seed));
    w.key("exit_code").value(run.exit_code);
    w.key("result").value(run.verdict);
    w.key("controlled").value(run.controlled);
    w.key("returned_to_hover").value(run.hover);
    w.key("sim_time_s").value(run.sim_time_s);
    w.key("wall_time_s").value(run.wall_time_s);
    w.key("figures").begin_object();
    for (const auto& [k, v] : run.figures) w.key(k).value(v);
    w.end_object();
    w.end_object();
  }
  w.end_array();
  w.end_object();
  return w.str();
}

std::string sweep_csv(const SweepResult& r) {
  std::ostringstream out;
  out.precision(10);
  out << "set,label,seed,exit_code,result,controlled,returned_to_hover,sim_time_s,wall_time_s";
  for (const auto& fig : sweep_figures()) out << "," << fig.key;
  out << "\n";
  const auto quoted = [](const std::string& s) {
    std::string q = "\"";
    for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
    return q + "\"";
  };
  for (const auto& run : r.runs) {
    out << run.set + 1 << "," << quoted(r.sets[run.set].label) << "," << run.seed << "," << run.exit_code << ","
        << quoted(run.verdict) << "," << run.controlled << "," << run.hover << "," << run.sim_time_s << ","
        << run.wall_time_s;
    for (const auto& fig : sweep_figures()) {
      const auto it = run.figures.find(fig.key);
      out << ",";
      if (it != run.figures.end()) out << it->second;
    }
    out << "\n";
  }
  return out.str();
}

}  // namespace nimble::launcher
