/// bench_rig: the rig's timing figures, measured on the real executables through `rig run`.
///
///   bench_rig [scenario.yaml] [--runs N]
///
/// Prints, for the scenario (default rig_configs/id_doublet_train_fast.yaml):
///  - real time: wake-up jitter p50/p99/max of the plant (1 kHz) and controller (512 Hz)
///    loops, and the control-loop latency TRUTH published -> ACTUATOR_CMD received at the
///    plant, p50/p99/max, with the scenario's run settings (rig_configs/run/realtime_lab.yaml)
///    and with plain defaults (timer-driven controller, no spinning, no CPU placement);
///  - real time on the estimator: the estimator's latency from an IMU sample's time to its
///    estimate going out, and the loop figures of that run;
///  - lockstep: speed in multiples of real time over N runs.
/// Targets: jitter p99 <= 50 us, latency p99 <= 150 us, lockstep >= 20x.

#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <vector>

#include <yaml-cpp/yaml.h>

namespace fs = std::filesystem;

namespace {

std::string self_dir() {
  std::error_code ec;
  const auto exe = fs::read_symlink("/proc/self/exe", ec);
  return ec ? std::string(".") : exe.parent_path().string();
}

YAML::Node run(const std::string& rig, const std::string& scenario, const std::string& args, const std::string& dir) {
  const std::string json = dir + "/summary.json";
  fs::remove(json);
  const std::string cmd = rig + " run " + scenario + " --no-progress --log " + dir + "/bench.lcmlog --json " + json +
                          " " + args + " > " + dir + "/out.txt 2>&1";
  const int status = std::system(cmd.c_str());
  if (!WIFEXITED(status) || WEXITSTATUS(status) != 0 || !fs::exists(json)) {
    std::fprintf(stderr, "bench_rig: '%s' failed; see %s/out.txt\n", cmd.c_str(), dir.c_str());
    std::exit(1);
  }
  return YAML::LoadFile(json);
}

void print_realtime(const char* label, const YAML::Node& s) {
  std::printf("\n%s\n", label);
  std::printf("  %-12s %10s %10s %10s\n", "loop", "p50 [us]", "p99 [us]", "max [us]");
  for (const char* p : {"plant", "controller"}) {
    const YAML::Node t = s["timing"][p];
    std::printf("  %-12s %10.1f %10.1f %10.1f\n", p, t["jitter_p50_us"].as<double>(), t["jitter_p99_us"].as<double>(),
                t["jitter_max_us"].as<double>());
  }
  const YAML::Node t = s["timing"]["plant"];
  std::printf("  %-12s %10.1f %10.1f %10.1f   (%lld commands)\n", "latency", t["latency_p50_us"].as<double>(),
              t["latency_p99_us"].as<double>(), t["latency_max_us"].as<double>(), t["latency_count"].as<long long>());
}

}  // namespace

int main(int argc, char** argv) {
  std::string scenario = std::string(RIG_SOURCE_DIR) + "/rig_configs/id_doublet_train_fast.yaml";
  int runs = 5;
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (a == "--runs" && i + 1 < argc) runs = std::max(1, std::atoi(argv[++i]));
    else scenario = a;
  }
  const std::string rig = self_dir() + "/rig";
  const std::string dir = (fs::temp_directory_path() / ("bench_rig_" + std::to_string(::getpid()))).string();
  fs::create_directories(dir);
  std::printf("bench_rig: %s\n", scenario.c_str());
  std::printf("machine: %ld CPUs online\n", ::sysconf(_SC_NPROCESSORS_ONLN));

  // The scenario as shipped: the controller flies on the estimator's output.
  const YAML::Node lab = run(rig, scenario, "--clock realtime", dir);
  const YAML::Node e = lab["timing"]["estimator"];
  std::printf("\nreal time, scenario as shipped (flying on the estimator)\n");
  if (e) {
    std::printf("  estimator: IMU sample time -> ESTIMATE published [us]\n");
    std::printf("  %-12s %10.1f %10.1f %10.1f   (%lld estimates)\n", "estimator", e["latency_p50_us"].as<double>(),
                e["latency_p99_us"].as<double>(), e["latency_max_us"].as<double>(),
                e["latency_count"].as<long long>());
  }
  print_realtime("  plant and controller (state-triggered controller, spin 100 us, CPU placement)"
                 "\n  controller row: lateness of each cycle behind the state that triggered it",
                 lab);

  // Ideal sensing, plant and controller alone: the rig's own control-loop latency.
  const std::string ideal = "--set run.controller_input=truth --set processes=[plant,controller]";
  print_realtime("real time, ideal sensing (plant and controller only), scenario run settings",
                 run(rig, scenario, "--clock realtime " + ideal, dir));
  print_realtime("real time, ideal sensing, plain defaults (timer-driven controller, sleeping waits, no CPU placement)"
                 "\n  latency includes the wait for the controller's next 512 Hz deadline",
                 run(rig, scenario,
                     "--clock realtime " + ideal +
                         " --set run.controller_trigger=timer --set run.spin_us=0 "
                         "--set run.rig_cpus=[] --set run.launcher_cpus=[]",
                     dir));

  const auto lockstep_speed = [&](const std::string& label, const std::string& args) {
    std::vector<double> speeds;
    for (int i = 0; i < runs; ++i) speeds.push_back(run(rig, scenario, "--clock lockstep " + args, dir)["speed_x_realtime"].as<double>());
    std::sort(speeds.begin(), speeds.end());
    std::printf("\nlockstep speed, %s, over %d runs [x real time]: min %.1f, median %.1f, max %.1f\n", label.c_str(),
                runs, speeds.front(), speeds[speeds.size() / 2], speeds.back());
  };
  lockstep_speed("scenario as shipped", "");
  lockstep_speed("ideal sensing (plant and controller only)", ideal);
  std::printf("\ntargets: jitter p99 <= 50 us, latency p99 <= 150 us, lockstep >= 20x\n");
  fs::remove_all(dir);
  return 0;
}
