#pragma once
/// A rig log (LCM) as an indexed MCAP file, for Foxglove, Lichtblick and PlotJuggler.
///
/// One MCAP channel per LCM channel, its topic the LCM channel's name (`TRUTH`), its messages
/// JSON (message encoding `json`) described by the type's JSON Schema (schema encoding
/// `jsonschema`, schema name the type's full name, `nimble.truth_state_t`); see
/// lcmjson/lcm_json.h for both.
///
/// Times: log_time is the message's rig (simulated) time, so that every channel of a run lines
/// up on the rig's clock whatever the run's clock was. A message whose type has no rig time,
/// or holds -1 there (the wall-clock channels, HEARTBEAT), gets the newest rig time of the log
/// before it (0 before any). publish_time is the log event's own timestamp, sequence the log's
/// event number (its low 32 bits).
///
/// A message that is not exactly one message of its channel's type (garbage a fault test put on
/// the bus, recorded like everything else) is left out of the JSON channel and counted.
/// Channels the rig's contract does not know have no JSON channel; they are counted.
///
/// Physical bounds (ExportOptions::vehicle): a message with a field beyond the vehicle's bounds
/// (contract/message_bounds.h: garbage that decoded) is left out of the JSON channel and named by
/// channel, field, time and count (ExportStats::beyond); with `strict` the export is refused
/// instead (ident::RefusedData), and no MCAP file is left.
///
/// raw: every LCM channel also as `<CHANNEL>/lcm` with the exact LCM bytes of every event
/// (message encoding `lcm`), the type's .lcm source text as its schema (encoding `lcm`); an
/// unknown channel as raw only, without a schema.
///
/// The metadata record "rig" holds the log's file name and, when `<log>.scenario.yaml` lies
/// beside the log, the resolved scenario of the run.

#include <cstdint>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "core/data_bounds.h"
#include "core/json_line.h"
#include "core/vehicle.h"
#include "lcmlog/lcm_log.h"
#include "mcap/mcap_writer.h"

namespace nimble::mcap {

struct ExportOptions {
  Compression compression = Compression::kZstd;
  bool raw = false;      ///< also `<CHANNEL>/lcm` with the LCM bytes
  bool salvage = false;  ///< a damaged log: export the events before the damage
  std::size_t chunk_size = 2u << 20;
  int zstd_level = WriterOptions{}.zstd_level;
  /// Check the messages against this vehicle's data bounds (none: not checked).
  std::optional<Vehicle> vehicle;
  bool strict = false;  ///< a message beyond the bounds refuses the export
};

/// One LCM channel of the log.
struct ChannelExport {
  std::string type;            ///< full type name, "" for a channel the contract does not know
  uint64_t events = 0;         ///< events of the channel in the log
  uint64_t json = 0;           ///< messages written as JSON
  uint64_t undecodable = 0;    ///< events that are not exactly one message of the type
  uint64_t beyond_bounds = 0;  ///< messages left out with a field beyond the vehicle's bounds
  uint64_t raw = 0;            ///< messages written to `<CHANNEL>/lcm`
};

struct ExportStats {
  std::string log, out;
  Compression compression = Compression::kZstd;
  std::map<std::string, ChannelExport> channels;  ///< by LCM channel name
  std::vector<std::string> unknown_channels;      ///< channels the contract does not know
  uint64_t events = 0;                            ///< events read from the log
  uint64_t messages = 0;                          ///< MCAP messages written (JSON and raw)
  uint64_t undecodable = 0;                       ///< over every channel
  uint64_t unknown_events = 0;                    ///< events on unknown channels
  uint64_t mcap_channels = 0;
  uint64_t start_time_ns = 0, end_time_ns = 0;  ///< log times of the first and last message
  uint64_t bytes_in = 0, bytes_out = 0;
  double seconds = 0.0;
  std::string damage;                 ///< salvaging: what was wrong with the log ("" if it was whole)
  uint64_t beyond_bounds = 0;         ///< messages left out, over every channel
  std::optional<BoundsTally> beyond;  ///< their fields, when the export checked the bounds
};

/// Writes the rig log `log_path` as MCAP to `out_path` (through `<out_path>.part`).
/// @throws ident::DataError for a damaged log (naming the byte offset and the event) unless
///         salvaging; ident::RefusedData for a message beyond the bounds with `strict`; WriteError when the file cannot be written; std::invalid_argument when
///         `out_path` is the log itself.
ExportStats export_log_to_mcap(const std::string& log_path, const std::string& out_path,
                               const ExportOptions& options = {});

/// One line for people: messages, channels, size, compression, time; what was left out, by channel.
std::string summary_line(const ExportStats& stats);

/// Undecodable events by channel (ExportStats::channels), for undecodable_text() and --json.
std::map<std::string, uint64_t> undecodable_by_channel(const ExportStats& stats);

/// What an export left out, for people: "1 undecodable left out (MOCAP_POSE 1)", channels in
/// name order; "" when nothing was.
std::string undecodable_text(const std::map<std::string, uint64_t>& by_channel);

/// The undecodable messages by channel as the "undecodable_channels" object of a --json report.
OrderedJson undecodable_json(const std::map<std::string, uint64_t>& by_channel);

/// An export as `rig export --format mcap --json` reports it: counts, times, sizes, damage, and
/// per channel its type, events, JSON messages, undecodable and raw messages.
std::string export_json(const ExportStats& stats);

/// The messages of a rig log beyond the physical bounds (ExportOptions::vehicle's check, without
/// writing anything): their byte offsets in the log, the tally naming them, and any damage.
struct LogBounds {
  explicit LogBounds(const Vehicle& vehicle) : tally(vehicle) {}
  BoundsTally tally;
  std::vector<int64_t> offsets;
  std::string damage;
};
/// @throws ident::DataError for a damaged log unless salvaging.
LogBounds check_log_bounds(const std::string& log_path, const Vehicle& vehicle, bool salvage = false);

/// Counts, by channel, the events of a rig log that are not exactly one message of their
/// channel's type, by the test the MCAP export leaves them out by (lcmjson::to_json). Events on
/// channels the contract does not know are not counted. For readers that pass over the channels
/// they do not use (ident::LogReadOptions::other_event), so that they can say what they left.
class UndecodableCount {
 public:
  void add(const lcmlog::LogEventRecord& event);
  const std::map<std::string, uint64_t>& by_channel() const { return by_channel_; }
  uint64_t total() const;

 private:
  std::map<std::string, uint64_t> by_channel_;
};

}  // namespace nimble::mcap
