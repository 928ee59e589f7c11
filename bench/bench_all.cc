/// bench_all: every speed ratio of the rig against its floor, measured in one run, in one table
/// and one JSON that a later change can be compared with.
///
///   bench_all [--runs N] [--json FILE]
///
/// Runs, beside this program, each with N runs (default 3; medians):
///  - bench_ekf: the EKF per second of flight against a bare predict + update of the same model;
///  - bench_inprocess --flights-only: in process against the plant model alone, and the
///    estimator's path per simulated second (every process minus the run without the estimator);
///  - bench_rig: real time against the bare LCM chain (latency p50 and p99, quiet and loaded,
///    with the latency budget stage by stage) and lockstep against the bare stepping protocol.
/// Then prints each ratio beside its target (docs/timing.md, "Speed") and whether it meets it, and
/// with --json writes {"ratios": {...}, "targets": {...}, "ekf": ..., "inprocess": ..., "rig": ...}
/// (the three programs' own JSON under their names).
/// Not a test: the figures depend on the machine; the ratios travel. About 3 minutes.

#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "cmdline/args.h"

namespace fs = std::filesystem;

namespace {

std::string self_dir() {
  std::error_code ec;
  const auto exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

/// Runs `program args` beside this one with its output to `dir`/<program>.txt, and returns the
/// JSON it wrote. @throws std::runtime_error naming the program and its output if it failed.
nlohmann::json run(const std::string& program, const std::string& args, const std::string& dir) {
  const std::string json = dir + "/" + program + ".json", out = dir + "/" + program + ".txt";
  const std::string cmd = self_dir() + "/" + program + " " + args + " --json " + json + " > " + out + " 2>&1";
  std::printf("  %s %s ...\n", program.c_str(), args.c_str());
  std::fflush(stdout);
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !fs::exists(json)) {
    throw std::runtime_error("'" + cmd + "' failed; its output is in " + out);
  }
  std::ifstream in(json);
  return nlohmann::json::parse(in);
}

struct Ratio {
  std::string key, what;
  double value = 0.0, target = 0.0;
  bool at_least = true;  ///< the target is a lower bound (else an upper bound)
  bool meets() const { return at_least ? value >= target : value <= target; }
};

}  // namespace

int main(int argc, char** argv) {
  int runs = 3;
  std::string json_file;
  nimble::cmdline::CommandLine cl("bench_all",
                                  "Every speed ratio of the rig against its floor in one run: the EKF, in process, "
                                  "real\ntime (with its latency budget) and lockstep, each beside its target.");
  cl->footer("Not a test: the figures depend on the machine; the ratios travel.");
  cl->add_option("--runs", runs, "runs of each figure in each benchmark (medians)")
      ->check(CLI::Range(1, 100))
      ->type_name("N")
      ->capture_default_str();
  cl.add_json(json_file, "the ratios, their targets and each benchmark's own figures");
  if (const auto done = cl.parse(argc, argv)) return *done;
  const std::string dir = (fs::temp_directory_path() / ("bench_all_" + std::to_string(::getpid()))).string();
  fs::create_directories(dir);
  try {
    const std::string n = std::to_string(runs);
    std::printf("bench_all: %d runs of each figure\n", runs);
    const nlohmann::json ekf = run("bench_ekf", "60 --passes " + std::to_string(2 * runs - 1), dir);
    const nlohmann::json inprocess = run("bench_inprocess", "--flights-only --runs " + n, dir);
    const nlohmann::json rig = run("bench_rig", "--runs " + n, dir);

    const nlohmann::json& rt = rig["realtime"];
    const std::vector<Ratio> ratios = {
        {"inprocess_to_floor", "in process, log written / the plant model alone", inprocess["ratio_to_floor"], 0.12,
         true},
        {"estimator_path_to_bare_ekf", "the estimator's path in process / a bare EKF predict + update",
         inprocess["inprocess"]["estimator_path_us_per_s"].get<double>() / ekf["floor_us_per_s"].get<double>(), 1.5,
         false},
        {"ekf_to_bare_ekf", "the EKF alone (latency, rollback) / a bare EKF predict + update", ekf["ratio_to_floor"],
         1.5, false},
        {"realtime_p50_to_chain", "real time, loop latency p50 / the bare LCM chain's",
         rt["latency_p50_us"].get<double>() / rt["floor_latency_p50_us"].get<double>(), 1.4, false},
        {"realtime_p99_to_chain", "real time, loop latency p99 / the bare LCM chain's",
         rt["latency_p99_us"].get<double>() / rt["floor_latency_p99_us"].get<double>(), 1.6, false},
        {"realtime_loaded_p50_to_chain", "the same under a busy loop on every CPU, p50",
         rt["loaded"]["latency_p50_us"].get<double>() / rt["loaded"]["floor_latency_p50_us"].get<double>(), 1.4, false},
        {"realtime_loaded_p99_to_chain", "the same under a busy loop on every CPU, p99",
         rt["loaded"]["latency_p99_us"].get<double>() / rt["loaded"]["floor_latency_p99_us"].get<double>(), 1.6, false},
        {"lockstep_to_limit", "lockstep speed / the bare stepping protocol's",
         rig["lockstep"]["speed_x"].get<double>() / rig["lockstep"]["limit_speed_x"].get<double>(), 0.65, true},
    };
    std::printf("\n%-66s %8s %8s  %s\n", "ratio", "value", "target", "");
    nlohmann::json out_ratios = nlohmann::json::object(), targets = nlohmann::json::object();
    int missed = 0;
    for (const Ratio& r : ratios) {
      std::printf("%-66s %8.3f %s%7.3f  %s\n", r.what.c_str(), r.value, r.at_least ? ">=" : "<=", r.target,
                  r.meets() ? "meets" : "misses");
      out_ratios[r.key] = r.value;
      targets[r.key] = {{r.at_least ? "at_least" : "at_most", r.target}, {"meets", r.meets()}};
      missed += r.meets() ? 0 : 1;
    }
    std::printf("\n%d of %zu targets met; each benchmark's own report is in its output (%s while this runs)\n",
                static_cast<int>(ratios.size()) - missed, ratios.size(), dir.c_str());
    if (!json_file.empty()) {
      const nlohmann::json j{{"runs", runs},
                             {"ratios", out_ratios},
                             {"targets", targets},
                             {"ekf", ekf},
                             {"inprocess", inprocess},
                             {"rig", rig},
                             {"cpus", ::sysconf(_SC_NPROCESSORS_ONLN)}};
      nimble::cmdline::write_json(json_file, j.dump(2));
    }
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_all: %s\n", e.what());
    fs::remove_all(dir);
    return 1;
  }
  fs::remove_all(dir);
  return 0;
}
