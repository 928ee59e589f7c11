/// What the commands that read flight data share (cli/log_input.h).

#include "cli/log_input.h"

#include <filesystem>
#include <iostream>
#include <stdexcept>

#include "core/config.h"
#include "estimator/sensing_config.h"
#include "ident/flight_sensing.h"

namespace nimble::cli {

ident::TimeRange time_range(const std::string& text) {
  const std::size_t colon = text.find(':');
  double start = NAN, end = NAN;
  if (colon == std::string::npos || !CLI::detail::lexical_cast(text.substr(0, colon), start) ||
      !CLI::detail::lexical_cast(text.substr(colon + 1), end) || !std::isfinite(start) || !std::isfinite(end)) {
    throw std::invalid_argument("'" + text + "' is not START:END in seconds");
  }
  if (!(end > start)) throw std::invalid_argument("'" + text + "': END must be after START");
  return {start, end};
}

std::vector<std::string> split_list(const std::string& text) {
  std::vector<std::string> out;
  std::size_t start = 0;
  while (start <= text.size()) {
    const std::size_t comma = text.find(',', start);
    const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    if (!item.empty()) out.push_back(item);
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  if (out.empty()) throw std::invalid_argument("empty list");
  return out;
}

/// --rate, --cutoff, --order, --interpolation: the processing every analysis command shares.
void add_processing(cmdline::CommandLine& cl, ident::ProcessingOptions& p) {
  cl->add_option("--rate", p.rate_hz, "resampling rate [Hz]")
      ->check(cmdline::kFinite & CLI::Range(1e-3, 1e6))
      ->capture_default_str()
      ->type_name("HZ");
  cl->add_option("--cutoff", p.cutoff_hz, "low-pass cut-off [Hz]")
      ->check(cmdline::kFinite & CLI::PositiveNumber)
      ->capture_default_str()
      ->type_name("HZ");
  cl->add_option("--order", p.filter_order, "Butterworth order, 0 = no low-pass")
      ->check(CLI::Range(0, 40))
      ->capture_default_str()
      ->type_name("N");
  cmdline::each_value(cl->add_option("--interpolation", "resampling of every channel: cubic (default) or linear")
                          ->type_name("MODE")
                          ->check(CLI::IsMember({"cubic", "linear"})),
                      [&p](const std::string& v) { p.interpolation = ident::interpolation_from_string(v); });
}

/// --salvage: read a damaged log up to the damage.
void add_salvage(cmdline::CommandLine& cl, ident::LogReadOptions& o) {
  cl->add_flag("--salvage", o.salvage, "a damaged rig log: read the events before the damage and say what was left");
}

/// --states SOURCE and --sensing FILE: where a rig log's states come from, and the sensing the
/// smoother's filter is matched to.
CLI::Option* add_states(cmdline::CommandLine& cl, ident::LogReadOptions& o, std::string& sensing_file) {
  auto* states = cmdline::each_value(
      cl->add_option("--states",
                     "rig log: where the states come from: auto (the estimator's if the log has "
                     "them, else the truth), estimate, truth, or smoothed (made offline from the "
                     "log's IMU and motion capture by the fixed-interval smoother, as the thesis's "
                     "identification data were), or sensors (the raw channels as a lab records them, "
                     "no fusion: p q r the IMU's gyro at its own stamps, phi theta psi each motion-"
                     "capture frame's attitude at mid-exposure, u v w its positions differentiated)")
          ->type_name("SOURCE")
          ->check(CLI::IsMember({"auto", "estimate", "truth", "smoothed", "sensors"})),
      [&o](const std::string& v) { o.states = ident::state_source_from_name(v); });
  cl->add_option("--sensing", sensing_file,
                 "--states smoothed or sensors: the sensing the flight flew with (its IMU, motion capture, velocity "
                 "differentiator and EKF; default rig_configs/sensing/default_sensing.yaml)")
      ->type_name("FILE");
  return states;
}

std::optional<int> apply_states(const cmdline::CommandLine& cl, ident::LogReadOptions& o,
                                const std::string& sensing_file, const std::vector<std::string>& data_files) {
  if (o.states == ident::StateSource::kAuto) return std::nullopt;
  for (const std::string& file : data_files) {
    // (a file that is not there is named by the reader)
    if (std::filesystem::exists(file) && !ident::is_lcm_log(file)) {
      return cl.fail("--states: " + file + " is not a rig log; a CSV file carries its own states");
    }
  }
  if (o.states != ident::StateSource::kSmoothed && o.states != ident::StateSource::kSensors) return std::nullopt;
  try {
    const SensingConfig sensing = load_sensing_config(sensing_file.empty() ? NIMBLE_DEFAULT_SENSING : sensing_file);
    o.smoothing = ident::smoothing_options(sensing);
  } catch (const ConfigError& e) {
    return cl.fail(std::string("--sensing: ") + e.what());
  }
  return std::nullopt;
}

/// --vehicle FILE.
void add_vehicle(cmdline::CommandLine& cl, std::string& file, const std::string& default_text) {
  cl->add_option("--vehicle", file, "the vehicle (default " + default_text + ")")->type_name("FILE");
}

/// Says on stderr what a salvaged read left out.
void warn_damage(const char* command, const std::string& file, const std::string& damage) {
  if (!damage.empty()) std::cerr << command << ": warning: " << file << ": " << damage << "\n";
}

/// Counts the undecodable messages a log reader passes over (the channels it does not read), as
/// the MCAP export counts what it leaves out: `o.other_event` feeds `count`.
void count_undecodable(ident::LogReadOptions& o, mcap::UndecodableCount& count) {
  o.other_event = [&count](const lcmlog::LogEventRecord& e) { count.add(e); };
}

/// Says on stderr which messages beyond the vehicle's physical bounds a read left out.
void warn_beyond_bounds(const char* command, const std::string& file, const BoundsTally& beyond) {
  if (!beyond.empty()) std::cerr << command << ": warning: " << file << ": left out: " << beyond.text() << "\n";
}

/// Says on stderr which undecodable messages a read left out, by channel and count.
void warn_undecodable(const char* command, const std::string& file, const mcap::UndecodableCount& count) {
  const std::string text = mcap::undecodable_text(count.by_channel());
  if (!text.empty()) std::cerr << command << ": warning: " << file << ": " << text << "\n";
}

}  // namespace nimble::cli
