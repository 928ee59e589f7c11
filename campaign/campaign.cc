#include "campaign/campaign.h"

#include <fcntl.h>
#include <sys/prctl.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <cstring>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <map>
#include <regex>
#include <sstream>
#include <stdexcept>

#include <nlohmann/json.hpp>

#include "campaign/worker_pool.h"
#include "core/descriptors.h"
#include "core/input_file.h"
#include "core/output_file.h"
#include "launcher/inprocess.h"
#include "scenario/scenario.h"
#include "transport/clock.h"

// The sweep manifest's parts as JSON (nlohmann's to_json/from_json, found by argument-dependent
// lookup in each type's namespace): an override as its command-line text, "key.path=value".
namespace nimble {
static void to_json(nlohmann::json& j, const Override& o) { j = o.key_path + "=" + o.value; }
static void from_json(const nlohmann::json& j, Override& o) { o = parse_override(j.get<std::string>()); }
}  // namespace nimble

namespace nimble::launcher {
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(ClusterSettings, partition, account, time_limit, cpus_per_task, memory_mb_per_cpu,
                                   chunk_size, rig)
}  // namespace nimble::launcher

namespace nimble::campaign {
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(Vary, key, values)
NLOHMANN_DEFINE_TYPE_NON_INTRUSIVE(SweepManifest, scenario, scenario_file, working_dir, overrides, vary, set_digests,
                                   first_seed, last_seed, clock, trace_hz, logs_dir, backend, cluster)
}  // namespace nimble::campaign

namespace nimble::campaign {

// One run is the launcher's (run plan, executors, report); a campaign flies many.
using namespace launcher;
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::json;

/// The manifest's "campaign": which command's campaign a directory holds.
constexpr const char* kSweepCampaign = "rig sweep";
constexpr const char* kRunFilePrefix = "run-";

/// Trace rate of a campaign with a report [Hz]: 50 samples per second of p, v and phi (the
/// doublets' roll-rate swings, 2-3 Hz, keep their peaks).
constexpr double kReportTraceHz = 50.0;

double unix_now() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

std::string self_exe() {
  std::error_code ec;
  const fs::path exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string("rig") : exe.string();
}

/// Runs per array task when none is given: a task should last long enough that Slurm's start of
/// it (about a second) is small beside it, and short enough that a cancelled or failed task loses
/// little. In process a run of the 30 s flight costs about 0.25 CPU seconds, in lockstep about 6,
/// in real time its 30 s (bench_campaign): about 25 s, 25 s and 30 s of work per task.
std::size_t default_chunk_size(const std::string& clock) {
  if (clock == kClockInprocess) return 100;
  if (clock == kClockLockstep) return 4;
  return 1;
}

/// The options of run `i`.
RunOptions run_options(const Campaign& c, std::size_t i, const std::string& bin_dir) {
  RunOptions r;
  r.scenario_file = c.scenario_file;
  r.overrides = c.overrides;
  const ParameterSet& set = c.sets.at(c.set_of(i));
  r.overrides.insert(r.overrides.end(), set.overrides.begin(), set.overrides.end());
  if (c.trace_hz > 0) r.overrides.push_back(Override{"summary.trace_hz", Json(c.trace_hz).dump()});
  r.clock = c.clock;
  r.seed = c.seed_of(i);
  r.bin_dir = bin_dir;
  r.progress = false;
  r.print_summary = false;
  return r;
}

/// The plan of parameter set `s`'s first run (its configuration digest names the set: the seed
/// is part of it).
/// @throws ConfigError naming the set.
RunPlan set_plan(const Campaign& c, std::size_t s) {
  const RunOptions o = run_options(c, s * c.seeds_per_set(), "");
  try {
    return load_run_plan(o);
  } catch (const ConfigError& e) {
    throw ConfigError(e.file(), e.key(), e.value(), e.problem() + " (in parameter set '" + c.sets[s].label + "')",
                      e.line());
  }
}

std::string run_tag(const Campaign& c, std::size_t i) {
  return "set" + std::to_string(c.set_of(i) + 1) + "-seed" + std::to_string(c.seed_of(i));
}

/// `rig run` itself for a clock other than in process (it makes its own network namespace), in a
/// child that does not outlive this worker; returns how it ended.
std::string run_rig(const RunOptions& options, const std::string& json_file, const std::string& log_file) {
  std::vector<std::string> args = {self_exe(),
                                   "run",
                                   options.scenario_file,
                                   "--clock",
                                   *options.clock,
                                   "--seed",
                                   std::to_string(*options.seed),
                                   "--json",
                                   json_file,
                                   "--log",
                                   log_file.empty() ? json_file + ".lcmlog" : log_file,
                                   "--no-progress"};
  for (const auto& ov : options.overrides) {
    args.push_back("--set");
    args.push_back(ov.key_path + "=" + ov.value);
  }
  std::vector<char*> argv;
  for (auto& a : args) argv.push_back(a.data());
  argv.push_back(nullptr);
  const pid_t worker = ::getpid();
  const pid_t pid = ::fork();
  if (pid < 0) throw std::runtime_error(std::string("rig sweep: fork failed: ") + std::strerror(errno));
  if (pid == 0) {
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != worker) ::_exit(kRunFailed);
    close_descriptors_from(STDERR_FILENO + 1);
    ::execv(argv[0], argv.data());
    std::fprintf(stderr, "cannot execute %s: %s\n", argv[0], std::strerror(errno));
    ::_exit(kRunFailed);
  }
  int status = 0;
  while (::waitpid(pid, &status, 0) < 0) {
    if (errno != EINTR) throw std::runtime_error(std::string("rig sweep: waitpid failed: ") + std::strerror(errno));
  }
  return exit_description(status);
}

/// In a worker: flies one run, with what it prints in `out_file` and its report in `json_file`;
/// returns how it ended ("exit code N", "killed by signal S").
std::string fly_run(const RunOptions& options, const std::string& json_file, const std::string& log_file,
                    const std::string& out_file) {
  std::fflush(stdout);
  std::fflush(stderr);
  const int saved_out = ::dup(STDOUT_FILENO), saved_err = ::dup(STDERR_FILENO);
  const int fd = ::open(out_file.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  if (fd >= 0) {
    ::dup2(fd, STDOUT_FILENO);
    ::dup2(fd, STDERR_FILENO);
    ::close(fd);
  }
  std::string how = "exit code " + std::to_string(kRunFailed);
  try {
    const RunPlan plan = load_run_plan(options);
    if (plan.inprocess()) {
      InprocessOptions io;
      io.log_file = log_file;
      const RunReport report = fly_inprocess(plan, io);
      try {
        write_file(json_file, report_json(report) + "\n");
        how = "exit code " + std::to_string(report.verdict.exit_code);
      } catch (const OutputError& e) {
        std::fprintf(stderr, "%s\n", e.what());
      }
    } else {
      how = run_rig(options, json_file, log_file);
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
  }
  std::fflush(stdout);
  std::fflush(stderr);
  for (const auto& [saved, target] : {std::pair{saved_out, STDOUT_FILENO}, std::pair{saved_err, STDERR_FILENO}}) {
    if (saved >= 0) {
      ::dup2(saved, target);
      ::close(saved);
    }
  }
  return how;
}

double number_or_nan(const Json& j, std::initializer_list<const char*> path) {
  const Json* n = &j;
  for (const char* key : path) {
    if (!n->is_object() || !n->contains(key)) return std::numeric_limits<double>::quiet_NaN();
    n = &(*n)[key];
  }
  return n->is_number() ? n->get<double>() : std::numeric_limits<double>::quiet_NaN();
}

/// The figures of a run from its `rig run --json` report.
void read_report(const Json& j, SweepRun& run) {
  constexpr double kDeg = 180.0 / M_PI;
  run.exit_code = j.at("exit_code").get<int>();
  run.verdict = j.at("result").get<std::string>();
  run.controlled = j.at("controlled").get<bool>();
  run.hover = j.at("returned_to_hover").get<bool>();
  run.sim_time_s = number_or_nan(j, {"sim_time_s"});
  run.wall_time_s = number_or_nan(j, {"wall_time_s"});
  run.speed_x_realtime = number_or_nan(j, {"speed_x_realtime"});
  auto& f = run.figures;
  f["max_abs_phi_deg"] = number_or_nan(j, {"max_abs", "phi"}) * kDeg;
  f["max_abs_p"] = number_or_nan(j, {"max_abs", "p"});
  f["max_abs_v"] = number_or_nan(j, {"max_abs", "v"});
  f["range_p"] = number_or_nan(j, {"ranges", "p"});
  f["range_v"] = number_or_nan(j, {"ranges", "v"});
  f["range_phi"] = number_or_nan(j, {"ranges", "phi"});
  f["range_delta_f"] = number_or_nan(j, {"ranges", "delta_f"});
  f["final_abs_phi_deg"] = std::fabs(number_or_nan(j, {"final", "phi"})) * kDeg;
  if (j.contains("estimator")) {
    f["est_phi_rms_deg"] = number_or_nan(j, {"estimator", "phi_rms_deg"});
    f["est_p_rms"] = number_or_nan(j, {"estimator", "p_rms_radps"});
    f["est_v_rms"] = number_or_nan(j, {"estimator", "v_rms_mps"});
  }
  for (auto it = f.begin(); it != f.end();) it = std::isfinite(it->second) ? std::next(it) : f.erase(it);
  if (j.contains("trace") && j["trace"].is_object()) {
    const Json& t = j["trace"];
    const auto series = [&t](const char* name) {
      std::vector<double> xs;
      if (!t.contains(name) || !t[name].is_array()) return xs;
      for (const auto& x : t[name])
        xs.push_back(x.is_number() ? x.get<double>() : std::numeric_limits<double>::quiet_NaN());
      return xs;
    };
    run.trace.dt_s = number_or_nan(t, {"dt_s"});
    run.trace.p = series("p");
    run.trace.v = series("v");
    run.trace.phi = series("phi");
    if (!(run.trace.dt_s > 0) || run.trace.v.size() != run.trace.p.size() ||
        run.trace.phi.size() != run.trace.p.size()) {
      run.trace = RunTrace{};
    }
  }
}

/// The sweep's campaign: its manifest (result_files.h), its keys those of SweepManifest.
Manifest manifest_of(const Campaign& c) {
  return Manifest{kSweepCampaign, Json(static_cast<const SweepManifest&>(c)), {}};
}

/// The sweep the manifest `m` describes, into `c`, its parameter sets made from its vary list.
/// @throws std::exception saying what is missing or wrong.
void read_sweep_manifest(const Manifest& m, Campaign& c) {
  m.fields.get_to(static_cast<SweepManifest&>(c));
  c.sets = parameter_sets(c.vary);
  if (c.set_digests.size() != c.sets.size()) {
    throw std::runtime_error("its " + std::to_string(c.set_digests.size()) + " set digests do not match the " +
                             std::to_string(c.sets.size()) + " sets of its vary list");
  }
  if (c.last_seed < c.first_seed) throw std::runtime_error("its seeds are out of order");
  if (c.backend != kBackendLocal && c.backend != kBackendSlurm)
    throw std::runtime_error("unknown backend " + c.backend);
  if (c.cluster.chunk_size == 0 || c.cluster.cpus_per_task < 1)
    throw std::runtime_error("chunk size or CPUs per task below 1");
  c.created_unix_s = m.made.is_null() ? 0.0 : m.made.at("unix_s").get<double>();
}

}  // namespace

std::size_t Campaign::chunk_count() const {
  const std::size_t n = run_count(), k = std::max<std::size_t>(cluster.chunk_size, 1);
  return (n + k - 1) / k;
}

std::vector<std::size_t> Campaign::chunk(std::size_t task) const {
  std::vector<std::size_t> runs;
  const std::size_t k = std::max<std::size_t>(cluster.chunk_size, 1);
  for (std::size_t i = task * k; i < std::min(run_count(), (task + 1) * k); ++i) runs.push_back(i);
  return runs;
}

std::string Campaign::run_name(std::size_t run) const {
  return "set " + std::to_string(set_of(run) + 1) + " seed " + std::to_string(seed_of(run));
}

std::string Campaign::run_key(std::size_t run) const {
  char name[32];
  std::snprintf(name, sizeof name, "%s%06zu", kRunFilePrefix, run);
  return name;
}

std::string trim(const std::string& s) {
  const auto a = s.find_first_not_of(" \t\r\n");
  if (a == std::string::npos) return "";
  return s.substr(a, s.find_last_not_of(" \t\r\n") - a + 1);
}

std::string last_line(const std::string& file) {
  std::ifstream in(file);
  std::string line, last;
  while (std::getline(in, line)) {
    if (!trim(line).empty()) last = trim(line);
  }
  return last;
}

Campaign create_campaign(const CampaignRequest& request) {
  const SweepOptions& o = request.sweep;
  Campaign c;
  c.scenario_file = fs::absolute(o.base.scenario_file).lexically_normal().string();
  c.working_dir = fs::current_path().string();
  c.overrides = o.base.overrides;
  c.vary = o.vary;
  c.sets = parameter_sets(o.vary);
  c.first_seed = o.first_seed;
  c.last_seed = o.last_seed;
  if (c.last_seed - c.first_seed >= 100000000ULL) {
    throw std::invalid_argument("--seeds: at most 100000000 seeds per parameter set");
  }
  c.clock = o.base.clock.value_or(kClockInprocess);
  c.trace_hz = request.report ? kReportTraceHz : 0.0;
  c.backend = request.backend;
  c.cluster = request.cluster;
  if (c.cluster.chunk_size == 0) c.cluster.chunk_size = default_chunk_size(c.clock);
  if (c.cluster.rig.empty()) c.cluster.rig = self_exe();

  // Every set's plan is loaded before anything is written: a bad value stops the campaign at once.
  RunPlan first;
  for (std::size_t s = 0; s < c.sets.size(); ++s) {
    RunPlan plan = set_plan(c, s);
    c.set_digests.push_back(scenario_digest(plan.scenario));
    if (s == 0) first = std::move(plan);
  }
  c.scenario = first.scenario.name;

  std::string dir = request.dir;
  if (dir.empty()) {
    char stamp[32];
    const std::time_t now = std::time(nullptr);
    std::strftime(stamp, sizeof stamp, "%Y%m%d-%H%M%S", std::localtime(&now));
    dir = "rig_campaigns/" + c.scenario + "-" + stamp + "-" + std::to_string(::getpid());
  }
  c.dir = fs::absolute(dir).lexically_normal().string();
  c.logs_dir = o.logs_dir.empty() ? "" : fs::absolute(o.logs_dir).lexically_normal().string();
  // The campaigns' one manifest: the directory is taken, and is new, empty or this campaign's.
  c.results = open_result_dir(c.dir, manifest_of(c));
  if (c.results.made()) write_file(c.dir + "/scenario.yaml", YAML::Dump(first.scenario.root) + "\n");
  if (!c.logs_dir.empty()) fs::create_directories(c.logs_dir);
  c.created_unix_s = load_campaign(c.dir).created_unix_s;
  return c;
}

Campaign load_campaign(const std::string& dir_in) {
  Campaign c;
  c.dir = fs::absolute(dir_in).lexically_normal().string();
  const std::string file = c.dir + "/campaign.json";
  const Manifest m = read_manifest(c.dir);  // a regular file within a campaign file's bound, of this rig's format
  if (m.campaign != kSweepCampaign) {
    throw std::runtime_error(c.dir + " holds no campaign of rig sweep (" + file + "'s campaign is \"" + m.campaign +
                             "\")");
  }
  try {
    read_sweep_manifest(m, c);
  } catch (const std::exception& e) {
    throw std::runtime_error("damaged campaign manifest " + file + ": " + e.what());
  }
  c.results = attach_result_dir(c.dir);
  return c;
}

Campaign open_campaign(const std::string& dir) {
  Campaign c = load_campaign(dir);
  c.results = open_result_dir(c.dir, read_manifest(c.dir));
  return c;
}

void enter_working_dir(const Campaign& c) {
  std::error_code ec;
  fs::current_path(c.working_dir, ec);
  if (ec) {
    throw std::runtime_error("cannot enter the campaign's working directory " + c.working_dir + " (" + ec.message() +
                             "): relative paths of its --set and --vary values resolve there, on every node");
  }
}

void check_campaign_inputs(const Campaign& c) {
  for (std::size_t s = 0; s < c.sets.size(); ++s) {
    const std::string now = scenario_digest(set_plan(c, s).scenario);
    if (now != c.set_digests[s]) {
      throw ConfigError(c.scenario_file, "", "",
                        "the scenario or a file it names changed since the campaign was made (parameter set " +
                            std::to_string(s + 1) + " '" + c.sets[s].label + "': configuration digest " + now +
                            ", the campaign's " + c.set_digests[s] + "); its runs would not be comparable");
    }
  }
}

std::vector<bool> finished_runs(const Campaign& c) {
  std::vector<bool> done(c.run_count(), false);
  const ResultFiles files = c.files();
  for (std::size_t i = 0; i < done.size(); ++i) done[i] = files.has(c.run_key(i));
  return done;
}

std::vector<std::size_t> missing_runs(const Campaign& c) {
  const std::vector<bool> done = finished_runs(c);
  std::vector<std::size_t> missing;
  for (std::size_t i = 0; i < done.size(); ++i) {
    if (!done[i]) missing.push_back(i);
  }
  return missing;
}

TemporaryCampaignDir::TemporaryCampaignDir() {
  static std::atomic<unsigned> made{0};
  path_ = (fs::temp_directory_path() /
           ("rig_sweep_" + std::to_string(::getpid()) + "_" + std::to_string(made.fetch_add(1) + 1)))
              .string();
  fs::remove_all(path_);
}

TemporaryCampaignDir::~TemporaryCampaignDir() {
  std::error_code ec;
  fs::remove_all(path_, ec);
}

void fly_campaign_runs(const Campaign& c, const std::vector<std::size_t>& runs, int jobs, const std::string& where,
                       const ProgressFn& progress) {
  std::vector<std::size_t> todo;
  for (const std::size_t i : runs) {
    if (i < c.run_count()) todo.push_back(i);
  }
  const std::string host = host_name();
  const fs::path work = fs::temp_directory_path() / ("rig_campaign_" + std::to_string(::getpid()));
  fs::remove_all(work);
  fs::create_directories(work);
  const std::string bin_dir = fs::path(self_exe()).parent_path().string();
  const auto files = [&](std::size_t i) {
    const std::string tag = run_tag(c, i);
    return std::array<std::string, 3>{(work / (tag + ".json")).string(), (work / (tag + ".out")).string(),
                                      c.logs_dir.empty() ? std::string() : c.logs_dir + "/" + tag + ".lcmlog"};
  };
  // A run's result: its index, set, seed, report (or why it has none) and where it ran.
  const auto result = [&](std::size_t i, const std::string& how, double started_s) {
    const auto f = files(i);
    Json r;
    r["index"] = i;
    r["set"] = c.set_of(i) + 1;
    r["seed"] = c.seed_of(i);
    try {
      r["report"] = Json::parse(read_input_file(f[0], InputKind::kCampaign));
      r["report"].at("exit_code").get<int>();
    } catch (const std::exception&) {
      const std::string said = last_line(f[1]);
      r["report"] = nullptr;
      r["failure"] = "failed: the run ended without a report (" + how + ")" + (said.empty() ? "" : ": " + said);
    }
    r["machine"] = {{"host", host},
                    {"where", where.empty() ? "local" : where},
                    {"started_unix_s", started_s},
                    {"finished_unix_s", unix_now()}};
    std::error_code ec;
    fs::remove(f[0], ec);
    fs::remove(f[1], ec);
    return r.dump();
  };

  // Each run in a worker of the pool, which hands back its result; run_kept writes its file as it
  // finishes (a run whose worker died has one too: a failed run, not a failed campaign).
  std::map<std::size_t, double> started;
  std::size_t not_ok = 0;
  PoolWork pool;
  pool.forget = true;
  pool.work = [&](std::size_t k) {
    const std::size_t i = todo[k];
    const auto f = files(i);
    const double start = unix_now();
    return result(i, fly_run(run_options(c, i, bin_dir), f[0], f[2], f[1]), start);
  };
  pool.died = [&](std::size_t k, const std::string& how) { return result(todo[k], how, started[todo[k]]); };
  pool.started = [&](std::size_t k) { started[todo[k]] = unix_now(); };
  pool.finished = [&](std::size_t, const std::string& r, std::size_t finished) {
    const Json j = Json::parse(r, nullptr, false);
    const bool ok = j.is_object() && j.contains("report") && j["report"].is_object() &&
                    j["report"].value("exit_code", -1) == kRunOk;
    if (!ok) ++not_ok;
    if (progress) progress(finished, not_ok);
  };
  KeptItems items;
  for (const std::size_t i : todo) items.keys.push_back(c.run_key(i));
  run_kept(items, jobs, pool, &c.files());
  std::error_code ec;
  fs::remove_all(work, ec);
}

SweepResult merge_campaign(const Campaign& c) {
  const std::vector<std::size_t> missing = missing_runs(c);
  if (!missing.empty()) {
    std::string names;
    for (std::size_t k = 0; k < std::min<std::size_t>(missing.size(), 5); ++k) {
      names += (k ? ", " : "") + c.run_name(missing[k]);
    }
    if (missing.size() > 5) names += ", ...";
    throw std::runtime_error(std::to_string(missing.size()) + " of " + std::to_string(c.run_count()) +
                             " runs have no result (" + names + ")");
  }
  SweepResult result;
  result.scenario = c.scenario;
  result.clock = c.clock;
  result.sets = c.sets;
  result.backend = c.backend;
  result.chunk_size = c.backend == kBackendSlurm ? c.cluster.chunk_size : 0;
  double last_end = c.created_unix_s;
  for (std::size_t i = 0; i < c.run_count(); ++i) {
    const std::string file = c.run_file(i);
    SweepRun run;
    run.set = c.set_of(i);
    run.seed = c.seed_of(i);
    try {
      const Json r = Json::parse(c.files().read(c.run_key(i)).value_or(""));
      if (r.at("index").get<std::size_t>() != i || r.at("seed").get<uint64_t>() != run.seed) {
        throw std::runtime_error("it holds another run (index " + r.at("index").dump() + ")");
      }
      if (r.at("report").is_null()) {
        run.exit_code = kRunFailed;
        run.verdict = r.at("failure").get<std::string>();
      } else {
        read_report(r.at("report"), run);
      }
      const Json& m = r.at("machine");
      run.host = m.at("host").get<std::string>();
      last_end = std::max(last_end, m.at("finished_unix_s").get<double>());
    } catch (const ForeignResult&) {
      throw;
    } catch (const std::exception& e) {
      throw std::runtime_error("damaged result file " + file + " (" + c.run_name(i) + "): " + e.what() +
                               "; delete it and `rig sweep --resume " + c.dir + "` flies the run again");
    }
    result.runs.push_back(std::move(run));
  }
  result.wall_time_s = last_end - c.created_unix_s;
  return result;
}

void progress_bar(std::size_t done, std::size_t total, std::size_t failed, double wall_s, bool tty) {
  // Not a terminal: a line at every tenth of the campaign, not one per run.
  if (!tty && done != total && done > 0 &&
      (done * 10 / std::max<std::size_t>(total, 1)) == ((done - 1) * 10 / std::max<std::size_t>(total, 1))) {
    return;
  }
  constexpr int kWidth = 30;
  const int filled = total > 0 ? static_cast<int>(kWidth * done / total) : kWidth;
  std::string bar(static_cast<std::size_t>(filled), '#');
  bar.resize(kWidth, '-');
  const std::string not_ok = failed == SIZE_MAX ? std::string() : ", " + std::to_string(failed) + " not ok";
  std::fprintf(stderr, "%s[%s] %zu/%zu runs%s, %.1f s%s", tty ? "\r" : "", bar.c_str(), done, total, not_ok.c_str(),
               wall_s, tty ? "" : "\n");
  if (tty && done == total) std::fprintf(stderr, "\n");
}

}  // namespace nimble::campaign
