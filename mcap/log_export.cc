#include "mcap/log_export.h"

#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <stdexcept>
#include <unordered_map>

#include "core/input_file.h"
#include "contract/message_bounds.h"
#include "ident/data_check.h"
#include "lcmlog/lcm_log.h"
#include "lcmjson/lcm_json.h"

namespace nimble::mcap {
namespace {

namespace fs = std::filesystem;

// The MCAP registry has no LCM entry: "lcm" is this project's name for both the message encoding
// (the bytes of one LCM message, fingerprint first) and the schema encoding (the text of the
// .lcm file declaring the type). Viewers show such channels without decoding them.
constexpr const char* kLcmEncoding = "lcm";

/// What the export knows of one LCM channel once it has seen it.
struct ChannelState {
  const lcmjson::LcmStruct* type = nullptr;  ///< nullptr: the contract does not know the channel
  uint16_t json_channel = 0;
  uint16_t raw_channel = 0;
  ChannelExport* stats = nullptr;
};

/// The scenario recorded beside a log; one that cannot be read, or is no regular file within a
/// configuration file's bound, is named instead of read.
std::string scenario_text(const std::string& file) {
  try {
    return read_input_file(file, InputKind::kConfig);
  } catch (const InputFileError& e) {
    return std::string("(not read: ") + e.what() + ")";
  }
}

uint64_t ns_from_us(int64_t us) { return us > 0 ? static_cast<uint64_t>(us) * 1000u : 0u; }

}  // namespace

ExportStats export_log_to_mcap(const std::string& log_path, const std::string& out_path, const ExportOptions& options) {
  const auto t0 = std::chrono::steady_clock::now();
  std::error_code ec;
  if (fs::exists(out_path, ec) && fs::equivalent(log_path, out_path, ec)) {
    throw std::invalid_argument("the MCAP file " + out_path + " is the log itself");
  }
  ExportStats stats;
  stats.log = log_path;
  stats.out = out_path;
  stats.compression = options.compression;
  if (options.vehicle) stats.beyond.emplace(*options.vehicle);

  lcmlog::LcmLogReader reader(log_path, options.salvage);  // throws DataError for a file that is no log
  WriterOptions wo;
  wo.compression = options.compression;
  wo.chunk_size = options.chunk_size;
  wo.zstd_level = options.zstd_level;
  wo.library = std::string("nimble-rig ") + NIMBLE_RIG_VERSION;
  McapWriter writer(out_path, wo);

  std::unordered_map<std::string, ChannelState> channels;
  std::unordered_map<const lcmjson::LcmStruct*, uint16_t> json_schemas, lcm_schemas;
  auto channel_state = [&](const std::string& name) -> ChannelState& {
    auto it = channels.find(name);
    if (it != channels.end()) return it->second;
    ChannelState s;
    s.type = lcmjson::rig_type_for_channel(name);
    s.stats = &stats.channels[name];
    if (s.type != nullptr) {
      s.stats->type = s.type->full_name();
      uint16_t& schema = json_schemas[s.type];
      if (schema == 0) schema = writer.add_schema(s.type->full_name(), "jsonschema", lcmjson::json_schema(*s.type));
      s.json_channel = writer.add_channel(schema, name, "json");
      ++stats.mcap_channels;
    } else {
      stats.unknown_channels.push_back(name);
    }
    if (options.raw) {
      uint16_t schema = 0;
      if (s.type != nullptr) {
        uint16_t& lcm = lcm_schemas[s.type];
        if (lcm == 0) lcm = writer.add_schema(s.type->full_name(), kLcmEncoding, s.type->source);
        schema = lcm;
      }
      s.raw_channel = writer.add_channel(schema, name + "/lcm", kLcmEncoding);
      ++stats.mcap_channels;
    }
    return channels.emplace(name, s).first->second;
  };

  lcmlog::LogEventRecord ev;
  lcmjson::JsonMessage json;
  int64_t newest_rig_time_us = 0;
  bool any = false;
  auto note_time = [&](uint64_t t) {
    if (!any || t < stats.start_time_ns) stats.start_time_ns = t;
    if (!any || t > stats.end_time_ns) stats.end_time_ns = t;
    any = true;
  };
  while (reader.next(&ev)) {
    ++stats.events;
    ChannelState& ch = channel_state(ev.channel);
    ++ch.stats->events;
    const uint32_t sequence = static_cast<uint32_t>(ev.event_number);
    const uint64_t publish_ns = ns_from_us(ev.timestamp_us);
    uint64_t log_ns = static_cast<uint64_t>(newest_rig_time_us) * 1000u;
    if (ch.type == nullptr) {
      ++stats.unknown_events;
    } else if (const std::string problem = lcmjson::to_json(*ch.type, ev.data.data(), ev.data.size(), &json);
               !problem.empty()) {
      ++ch.stats->undecodable;
      ++stats.undecodable;
    } else {
      const int64_t t_us = json.rig_time_us != -1 ? json.rig_time_us : newest_rig_time_us;  // its own time
      if (stats.beyond && contract::check_message_bounds(ev.channel, ev.data.data(), static_cast<int>(ev.data.size()),
                                                         static_cast<double>(t_us) * 1e-6, *stats.beyond,
                                                         ev.event_number) == contract::BoundsResult::kBeyond) {
        // Garbage that decoded: left out (its time, too, is no time the rig had).
        if (options.strict) throw ident::RefusedData(log_path, *stats.beyond);
        ++ch.stats->beyond_bounds;
        ++stats.beyond_bounds;
      } else {
        // Only -1 means "no rig time"; a negative time is no time the rig could have had either.
        if (json.rig_time_us >= 0) {
          log_ns = static_cast<uint64_t>(json.rig_time_us) * 1000u;
          if (json.rig_time_us > newest_rig_time_us) newest_rig_time_us = json.rig_time_us;
        }
        writer.add_message(ch.json_channel, sequence, log_ns, publish_ns, json.json.data(), json.json.size());
        ++ch.stats->json;
        note_time(log_ns);
      }
    }
    if (ch.raw_channel != 0) {
      writer.add_message(ch.raw_channel, sequence, log_ns, publish_ns, ev.data.data(), ev.data.size());
      ++ch.stats->raw;
      note_time(log_ns);
    }
  }
  stats.damage = reader.damage();

  std::map<std::string, std::string> rig{{"log", fs::path(log_path).filename().string()}};
  const std::string scenario_file = log_path + ".scenario.yaml";
  if (fs::exists(scenario_file, ec)) rig["scenario"] = scenario_text(scenario_file);
  if (!stats.damage.empty()) rig["damage"] = stats.damage;
  writer.add_metadata("rig", rig);
  writer.close();

  stats.messages = writer.stats().messages;
  stats.bytes_out = writer.stats().bytes;
  stats.bytes_in = fs::file_size(log_path, ec);
  if (ec) stats.bytes_in = 0;
  stats.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return stats;
}

LogBounds check_log_bounds(const std::string& log_path, const Vehicle& vehicle, bool salvage) {
  LogBounds out(vehicle);
  lcmlog::LcmLogReader reader(log_path, salvage);
  lcmlog::LogEventRecord ev;
  while (reader.next(&ev)) {
    const lcmjson::LcmStruct* type = lcmjson::rig_type_for_channel(ev.channel);
    if (type == nullptr) continue;
    const int64_t t_us = lcmjson::rig_time_us(*type, ev.data.data(), ev.data.size());
    if (contract::check_message_bounds(ev.channel, ev.data.data(), static_cast<int>(ev.data.size()),
                                       static_cast<double>(t_us) * 1e-6, out.tally,
                                       ev.event_number) == contract::BoundsResult::kBeyond) {
      out.offsets.push_back(ev.offset);
    }
  }
  out.damage = reader.damage();
  return out;
}

std::map<std::string, uint64_t> undecodable_by_channel(const ExportStats& stats) {
  std::map<std::string, uint64_t> out;
  for (const auto& [name, c] : stats.channels) {
    if (c.undecodable > 0) out[name] = c.undecodable;
  }
  return out;
}

std::string undecodable_text(const std::map<std::string, uint64_t>& by_channel) {
  uint64_t total = 0;
  std::string list;
  for (const auto& [name, n] : by_channel) {
    if (n == 0) continue;
    total += n;
    list += (list.empty() ? "" : ", ") + name + " " + std::to_string(n);
  }
  if (total == 0) return "";
  return std::to_string(total) + " undecodable left out (" + list + ")";
}

void UndecodableCount::add(const lcmlog::LogEventRecord& event) {
  const lcmjson::LcmStruct* type = lcmjson::rig_type_for_channel(event.channel);
  if (type == nullptr) return;  // a channel the contract does not know: nothing to decode it as
  thread_local lcmjson::JsonMessage json;
  if (!lcmjson::to_json(*type, event.data.data(), event.data.size(), &json).empty()) ++by_channel_[event.channel];
}

uint64_t UndecodableCount::total() const {
  uint64_t n = 0;
  for (const auto& [name, count] : by_channel_) n += count;
  return n;
}

std::string summary_line(const ExportStats& s) {
  std::size_t lcm_channels = s.channels.size();
  char size[64];
  const double mib = static_cast<double>(s.bytes_out) / (1024.0 * 1024.0);
  std::snprintf(size, sizeof size, "%.1f MiB", mib);
  char seconds[32];
  std::snprintf(seconds, sizeof seconds, "%.2f s", s.seconds);
  std::string line = std::to_string(s.messages) + " messages on " + std::to_string(s.mcap_channels) +
                     " MCAP channels (" + std::to_string(lcm_channels) + " LCM channels) -> " + s.out + ", " + size +
                     " (" + to_string(s.compression) + "), " + seconds;
  if (s.undecodable > 0) line += "; " + undecodable_text(undecodable_by_channel(s));
  if (s.beyond_bounds > 0) {
    std::string list;
    for (const auto& [name, c] : s.channels) {
      if (c.beyond_bounds > 0) list += (list.empty() ? "" : ", ") + name + " " + std::to_string(c.beyond_bounds);
    }
    line += "; " + std::to_string(s.beyond_bounds) + " beyond the physical bounds left out (" + list + ")";
  }
  if (s.unknown_events > 0) {
    line += "; " + std::to_string(s.unknown_events) + " events on " + std::to_string(s.unknown_channels.size()) +
            " unknown channels";
  }
  return line;
}

OrderedJson undecodable_json(const std::map<std::string, uint64_t>& by_channel) {
  OrderedJson j = OrderedJson::object();
  for (const auto& [name, n] : by_channel) j[name] = n;
  return j;
}

std::string export_json(const ExportStats& s) {
  OrderedJson j;
  j["log"] = s.log;
  j["out"] = s.out;
  j["format"] = "mcap";
  j["compression"] = to_string(s.compression);
  j["events"] = s.events;
  j["messages"] = s.messages;
  j["mcap_channels"] = s.mcap_channels;
  j["undecodable"] = s.undecodable;
  j["unknown_channel_events"] = s.unknown_events;
  j["undecodable_channels"] = undecodable_json(undecodable_by_channel(s));
  j["start_time_ns"] = s.start_time_ns;
  j["end_time_ns"] = s.end_time_ns;
  j["bytes_in"] = s.bytes_in;
  j["bytes_out"] = s.bytes_out;
  j["seconds"] = s.seconds;
  j["damage"] = s.damage;
  j["beyond_bounds_messages"] = s.beyond_bounds;
  if (s.beyond) j["beyond_bounds"] = s.beyond->json();
  OrderedJson& channels = j["channels"] = OrderedJson::object();
  for (const auto& [name, c] : s.channels) {
    channels[name] = {{"type", c.type},
                      {"events", c.events},
                      {"json", c.json},
                      {"undecodable", c.undecodable},
                      {"beyond_bounds", c.beyond_bounds},
                      {"raw", c.raw}};
  }
  j["unknown_channels"] = s.unknown_channels;
  return json_line(j);
}

}  // namespace nimble::mcap
