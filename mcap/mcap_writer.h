#pragma once
/// A streaming writer of indexed MCAP files (the public MCAP specification, major version 0).
///
/// Layout written:
///   Magic, Header, data section { Chunk (Schema, Channel, Message records), Message Index per
///   channel of the chunk } ..., Metadata ..., DataEnd (CRC-32 of the data section),
///   summary section { Schemas, Channels, Statistics, Chunk Indexes, Metadata Indexes },
///   summary offset section (one Summary Offset per group), Footer (summary CRC), Magic.
///
/// Schemas and channels are written into the chunk that first needs them (and again in the
/// summary), so a reader that streams the file without the index finds them before their
/// messages. Messages may come in any log-time order: the chunk and file start/end times are
/// the minimum and maximum, and each message index is written in log-time order.
///
/// The file is written as `<path>.part` and renamed to `<path>` only by a successful close():
/// a failed or abandoned export never leaves a partial file under the final name. The part is
/// taken for this writer (core/output_lock.h) before it is truncated: a second writer of the same
/// file is refused (nimble::OutputBusy, naming the holder) and the first one's part stays whole.

#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <map>
#include <memory>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

namespace nimble::mcap {

/// The name the file `path` is written under until it is whole: `<path>.part`.
inline std::string part_file_of(const std::string& path) { return path + ".part"; }

/// Compression of the chunks.
enum class Compression { kNone, kZstd };

/// "none" or "zstd".
const char* to_string(Compression c);
/// From "none" or "zstd". @throws std::invalid_argument otherwise.
Compression compression_from_string(const std::string& text);

/// A failure writing the file (names the file and what failed).
class WriteError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

struct WriterOptions {
  Compression compression = Compression::kZstd;
  /// A chunk is closed when its uncompressed records reach this size [bytes].
  std::size_t chunk_size = 2u << 20;
  /// zstd level. Measured by bench_export on a 60 s hover flight's log (341k messages): level 1
  /// gives 0.57 of the LCM log's size in 1.0 s of export, level 3 0.63 in 1.3 s.
  int zstd_level = 1;
  /// Free-form writer name in the Header's `library` field.
  std::string library = "nimble-rig";
  /// The Header's profile ("" = none of the well-known profiles).
  std::string profile;
};

/// What the writer wrote (after close()).
struct WriterStats {
  uint64_t messages = 0;
  uint64_t chunks = 0;
  uint64_t bytes = 0;  ///< size of the file
  uint64_t uncompressed_chunk_bytes = 0;
  uint64_t compressed_chunk_bytes = 0;
};

class McapWriter {
 public:
  /// Creates `<path>.part` (replacing an old one).
  /// @throws WriteError naming the file if it cannot be created, std::invalid_argument for a
  ///         chunk size of zero or a zstd level out of range.
  McapWriter(const std::string& path, WriterOptions options = {});
  /// Without close(): removes `<path>.part`; nothing appears under `<path>`.
  ~McapWriter();
  McapWriter(const McapWriter&) = delete;
  McapWriter& operator=(const McapWriter&) = delete;

  /// Registers a schema; returns its id (1, 2, ...). `encoding` e.g. "jsonschema".
  uint16_t add_schema(const std::string& name, const std::string& encoding, const std::string& data);
  /// Registers a channel on schema `schema_id` (0: no schema); returns its id (1, 2, ...).
  /// @throws std::invalid_argument for an unknown schema id.
  uint16_t add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                       const std::map<std::string, std::string>& metadata = {});
  /// Appends one message (log and publish times in ns).
  /// @throws std::invalid_argument for an unknown channel id; WriteError on a write failure.
  void add_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
                   const void* data, std::size_t size);
  /// Appends a Metadata record (written between chunks, indexed in the summary).
  void add_metadata(const std::string& name, const std::map<std::string, std::string>& metadata);

  /// Writes the last chunk, DataEnd, the summary and the footer, flushes, closes and renames
  /// `<path>.part` to `<path>`.
  /// @throws WriteError naming the file and what failed (the `.part` file is removed).
  void close();

  const std::string& path() const { return path_; }
  const WriterStats& stats() const { return stats_; }

 private:
  struct Schema {
    std::string name, encoding, data;
  };
  struct Channel {
    uint16_t schema_id = 0;
    std::string topic, message_encoding;
    std::map<std::string, std::string> metadata;
    uint64_t count = 0;
    bool in_chunk = false;  ///< written to the current chunk already
  };
  struct ChunkIndex {
    uint64_t start_time = 0, end_time = 0, offset = 0, length = 0;
    std::vector<std::pair<uint16_t, uint64_t>> message_index_offsets;
    uint64_t message_index_length = 0;
    uint64_t compressed_size = 0, uncompressed_size = 0;
  };
  struct MetadataIndex {
    uint64_t offset = 0, length = 0;
    std::string name;
  };

  void write_schema_record(std::string& out, uint16_t id);
  void write_channel_record(std::string& out, uint16_t id);
  void flush_chunk();
  void write_out(const void* data, std::size_t size);  ///< to the file; CRC of the data section
  void fail(const std::string& what);                  ///< throws WriteError; removes the .part
  void check_open() const;

  std::string path_, part_path_;
  WriterOptions options_;
  std::FILE* file_ = nullptr;
  uint64_t offset_ = 0;    ///< bytes written to the file
  uint32_t data_crc_ = 0;  ///< CRC-32 of every byte written so far (the data section until DataEnd)
  bool closed_ = false;

  std::vector<Schema> schemas_;  ///< id = index + 1
  std::vector<bool> schema_in_chunk_;
  std::vector<Channel> channels_;  ///< id = index + 1

  // The open chunk.
  std::string chunk_;                                                    ///< uncompressed records
  std::vector<std::vector<std::pair<uint64_t, uint64_t>>> chunk_index_;  ///< per channel: (log time, offset)
  std::vector<uint16_t> chunk_channels_;  ///< channels with messages in the chunk, in first-seen order
  uint64_t chunk_start_ = 0, chunk_end_ = 0;
  bool chunk_has_messages_ = false;

  std::string compressed_;  ///< reused compression buffer
  std::string scratch_;     ///< reused record buffer
  struct ZstdContext;
  std::unique_ptr<ZstdContext> zstd_;

  std::vector<ChunkIndex> chunk_indexes_;
  std::vector<MetadataIndex> metadata_indexes_;
  uint64_t message_start_ = 0, message_end_ = 0;
  WriterStats stats_;
};

}  // namespace nimble::mcap
