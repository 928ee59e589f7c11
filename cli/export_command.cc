/// `rig export`: a rig log as identification CSV, or as MCAP for Foxglove, Lichtblick and PlotJuggler.

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <iostream>
#include <map>
#include <stdexcept>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "contract/default_rates.h"
#include "core/data_bounds.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/data_check.h"
#include "ident/identify.h"
#include "ident/flight_data.h"
#include "ident/rig_log.h"
#include "core/json_line.h"
#include "ident/signal.h"
#include "ident/report.h"
#include "mcap/log_export.h"
#include "cli/log_input.h"
#include "core/config.h"

namespace nimble::cli {
namespace {

/// `rig export --format mcap`: the log as MCAP, the one-line summary, the --json report.
int export_mcap(const std::string& log, const std::string& out, const mcap::ExportOptions& options,
                const std::string& json) {
  const mcap::ExportStats stats = mcap::export_log_to_mcap(log, out, options);
  warn_damage("rig export", log, stats.damage);
  if (stats.beyond) warn_beyond_bounds("rig export", log, *stats.beyond);
  (json == "-" ? std::cerr : std::cout) << "rig export: " << mcap::summary_line(stats) << "\n";
  if (!json.empty()) cmdline::write_json(json, mcap::export_json(stats));
  return 0;
}

}  // namespace

int run_export_command(const std::vector<std::string>& args) {
  std::string log, csv, out_file, format, compression = "zstd", json;
  bool raw = false;
  double rate_hz = contract::kDefaultImuRateHz;
  ident::LogReadOptions log_options;
  ident::Interpolation interpolation = ident::Interpolation::kCubic;
  cmdline::CommandLine cl(
      "rig export",
      "Writes a rig log as identification CSV (the format rig identify reads), every channel\n"
      "resampled onto one grid, or as MCAP for Foxglove, Lichtblick and PlotJuggler.\n"
      "CSV: states come from the estimator (ESTIMATE) when the log has it, else from the plant's\n"
      "truth; inputs from ACTUATOR_FB; phi_sp from ATTITUDE_SP. MCAP (docs/viewers.md): one\n"
      "channel per LCM channel, JSON messages with their JSON Schema, log time = rig time.\n"
      "A damaged log is an error naming the byte offset and the event; a message that is not one of\n"
      "its channel's type is left out and named, by channel and count (CSV: those of the channels it\n"
      "does not read; a damaged message on a channel it reads is an error naming the event). A message\n"
      "with a value beyond the vehicle's physical bounds (its data_bounds) is left out and named by\n"
      "channel, field, time and count (--strict: the export is refused).");
  cl->add_option("log", log, "the rig log (.lcmlog)")->required();
  cl->add_option("--format", format, "csv or mcap (default: mcap when --out ends in .mcap, else csv)")
      ->check(CLI::IsMember({"csv", "mcap"}))
      ->type_name("FORMAT");
  cl->add_option("--csv", csv, "the CSV file to write (--format csv)")->type_name("FILE");
  cl->add_option("--out", out_file, "the file to write (either format)")->type_name("FILE");
  auto* rate = cl->add_option("--rate", rate_hz, "CSV: the grid's rate [Hz]")
                   ->check(cmdline::kFinite & CLI::Range(1e-3, 100000.0))
                   ->capture_default_str()
                   ->type_name("HZ");
  auto* interp = cmdline::each_value(
      cl->add_option("--interpolation", "CSV: cubic (default) or linear")
          ->type_name("MODE")
          ->check(CLI::IsMember({"cubic", "linear"})),
      [&interpolation](const std::string& v) { interpolation = ident::interpolation_from_string(v); });
  std::string sensing_file;
  auto* states = add_states(cl, log_options, sensing_file);
  auto* comp = cl->add_option("--compression", compression, "MCAP: chunk compression, zstd or none")
                   ->check(CLI::IsMember({"zstd", "none"}))
                   ->capture_default_str()
                   ->type_name("C");
  auto* raw_flag = cl->add_flag("--raw", raw, "MCAP: also each channel's LCM bytes as <CHANNEL>/lcm");
  add_salvage(cl, log_options);
  std::string vehicle_file;
  bool strict = false;
  add_vehicle(cl, vehicle_file, ident::default_vehicle_file() + ": its data_bounds");
  cl->add_flag("--strict", strict,
               "refuse the log (exit 2) if a message has a value beyond the vehicle's physical bounds, instead of "
               "leaving it out with a warning");
  cl.add_json(json,
              "what was exported (CSV: samples, rate, columns, state source; MCAP: messages per channel; both: "
              "undecodable messages by channel, damage)");
  if (const auto done = cl.parse(args)) return *done;
  const Vehicle vehicle = load_vehicle(vehicle_file.empty() ? ident::default_vehicle_file() : vehicle_file);
  if (format.empty()) {
    const bool mcap_name = out_file.size() >= 5 && out_file.compare(out_file.size() - 5, 5, ".mcap") == 0;
    format = csv.empty() && mcap_name ? "mcap" : "csv";
  }
  if (format == "mcap") {
    for (const CLI::Option* o : {rate, interp, states}) {
      if (o->count() > 0) return cl.fail(o->get_name() + " is for --format csv");
    }
    if (!csv.empty()) return cl.fail("--csv is for --format csv; the MCAP file is --out");
    if (out_file.empty()) return cl.fail("--format mcap needs --out FILE");
    mcap::ExportOptions options;
    options.compression = mcap::compression_from_string(compression);
    options.raw = raw;
    options.salvage = log_options.salvage;
    options.vehicle = vehicle;
    options.strict = strict;
    return export_mcap(log, out_file, options, json);
  }
  for (const CLI::Option* o : {comp, raw_flag}) {
    if (o->count() > 0) return cl.fail(o->get_name() + " is for --format mcap");
  }
  if (!csv.empty() && !out_file.empty()) return cl.fail("--csv and --out both name the output: give one");
  if (csv.empty()) csv = out_file;
  if (csv.empty()) return cl.fail("--csv FILE (or --out FILE.mcap for MCAP) is required");
  mcap::UndecodableCount undecodable;
  count_undecodable(log_options, undecodable);
  if (const auto failed = apply_states(cl, log_options, sensing_file, {log})) return *failed;
  BoundsTally beyond(vehicle);
  log_options.beyond_bounds = &beyond;  // messages beyond the bounds are left out, never resampled
  const ident::RigLogData data = ident::read_rig_log(log, log_options.states, log_options);
  if (strict && !beyond.empty()) throw ident::RefusedData(log, beyond);
  warn_damage("rig export", log, data.damage);
  warn_undecodable("rig export", log, undecodable);
  warn_beyond_bounds("rig export", log, beyond);
  const ident::UniformData grid = ident::resample_uniform(data.measured, rate_hz, interpolation);
  ident::FlightData out;
  out.source = log;
  const std::vector<double> t(grid.t_s.data(), grid.t_s.data() + grid.t_s.size());
  for (const auto& [name, values] : grid.signals) {
    if (!ident::is_known_channel(name)) continue;
    out.channels[name] = ident::Channel{t, std::vector<double>(values.data(), values.data() + values.size())};
  }
  ident::write_flight_csv(out, csv);
  (json == "-" ? std::cerr : std::cout) << "rig export: " << grid.size() << " samples at " << rate_hz
                                        << " Hz (states from " << data.state_source << ") -> " << csv << "\n";
  if (!json.empty()) {
    OrderedJson j;
    j["log"] = log;
    j["csv"] = csv;
    j["samples"] = grid.size();
    j["rate_hz"] = rate_hz;
    j["interpolation"] = ident::to_string(interpolation);
    j["state_source"] = data.state_source;
    j["damage"] = data.damage;
    j["undecodable"] = undecodable.total();
    j["undecodable_channels"] = mcap::undecodable_json(undecodable.by_channel());
    j["beyond_bounds"] = beyond.json();
    OrderedJson& columns = j["columns"] = OrderedJson::array();
    for (const auto& [name, channel] : out.channels) columns.push_back(name);
    cmdline::write_json(json, json_line(j));
  }
  return 0;
}

}  // namespace nimble::cli
