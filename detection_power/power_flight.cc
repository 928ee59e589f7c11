#include "detection_power/power_flight.h"

#include <time.h>

#include <exception>
#include <algorithm>
#include <stdexcept>
#include <utility>

#include "ident/rig_log.h"
#include "launcher/inprocess.h"
#include "transport/clock.h"

namespace nimble::detection_power {
namespace {

double seconds_since(std::int64_t start_ns) { return static_cast<double>(transport::monotonic_ns() - start_ns) / 1e9; }

/// CPU time of this process [s].
double cpu_s() {
  timespec ts{};
  ::clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + 1e-9 * static_cast<double>(ts.tv_nsec);
}

/// Flies `plan` and assembles its messages; an error of the assembler is kept, not thrown
/// across the flight (the recording thread would end the run with it).
struct AssembledFlight {
  launcher::RunReport report;
  ident::RigLogData data;
  std::string error;
};

AssembledFlight fly_assembled(const launcher::RunPlan& plan, const std::string& log_file) {
  AssembledFlight out;
  ident::RigLogAssembler assembler(plan.scenario.name + " seed " + std::to_string(plan.scenario.seed) + " (in memory)");
  std::int64_t event = 0;
  launcher::InprocessOptions o;
  o.log_file = log_file;
  o.config_digest = false;  // the verdict is all a power flight keeps of its report
  o.on_message = [&](const std::string& channel, const void* data, int size) {
    if (!out.error.empty()) return;
    try {
      assembler.add(channel, data, size, event++);
    } catch (const std::exception& e) {
      out.error = e.what();
    }
  };
  out.report = launcher::fly_inprocess(plan, o);
  if (out.error.empty()) out.data = assembler.finish(ident::StateSource::kAuto);
  return out;
}

}  // namespace

void set_seed(launcher::RunPlan& plan, std::uint64_t seed) {
  plan.scenario.root = YAML::Clone(plan.scenario.root);  // copies of a plan share their tree
  plan.scenario.seed = seed;
  plan.scenario.root["seed"] = seed;
}

std::uint64_t flight_seed(std::uint64_t campaign_seed, std::uint64_t index) {
  // splitmix64 of the pair (Steele, Lea, Flood 2014): neighbouring campaigns and indices give
  // unrelated seeds.
  std::uint64_t z = campaign_seed * 0x9E3779B97F4A7C15ULL + index + 0x632BE59BD9B4E019ULL;
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
  z ^= z >> 31;
  return z % 9000000000000000ULL;
}

ident::FlightData fly_to_data(launcher::RunPlan plan, std::uint64_t seed, const std::string& log_file) {
  set_seed(plan, seed);
  AssembledFlight f = fly_assembled(plan, log_file);
  if (!f.error.empty()) throw std::runtime_error(f.error);
  if (f.report.verdict.exit_code == launcher::kRunFailed) throw std::runtime_error(f.report.verdict.text);
  return std::move(f.data.measured);
}

FlightOutcome fly_and_check(launcher::RunPlan plan, std::uint64_t seed, const FlightCheck& check,
                            const std::string& log_file) {
  FlightOutcome out;
  out.seed = seed;
  set_seed(plan, seed);
  const std::int64_t start_ns = transport::monotonic_ns();
  const double start_cpu = cpu_s();
  AssembledFlight f;
  try {
    f = fly_assembled(plan, log_file);
  } catch (const std::exception& e) {
    out.error = std::string("flight: ") + e.what();
    out.flight_s = seconds_since(start_ns);
    return out;
  }
  out.flight_s = seconds_since(start_ns);
  out.flight_cpu_s = cpu_s() - start_cpu;
  out.build_s = std::max(0.0, out.flight_s - f.report.wall_time_s);
  out.run_exit = f.report.verdict.exit_code;
  if (!f.error.empty()) {
    out.error = "flight data: " + f.error;
    return out;
  }
  const std::int64_t workflow_ns = transport::monotonic_ns();
  const double workflow_cpu = cpu_s();
  try {
    const ident::DiscrepancyResult r =
        ident::find_discrepancy(f.data.measured, check.model, check.vehicle, check.options);
    out.analysed = true;
    out.verdict = r.verdict;
    for (const auto& e : r.effects) out.named.push_back(e.name);
    for (const auto& pair : r.ambiguous) out.ambiguous.insert(out.ambiguous.end(), pair.begin(), pair.end());
  } catch (const std::exception& e) {
    out.error = std::string("workflow: ") + e.what();
  }
  out.workflow_s = seconds_since(workflow_ns);
  out.workflow_cpu_s = cpu_s() - workflow_cpu;
  return out;
}

}  // namespace nimble::detection_power
