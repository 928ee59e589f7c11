#include "mcap/mcap_writer.h"

#include <fcntl.h>
#include <unistd.h>
#include <zlib.h>
#include <zstd.h>

#include <cerrno>
#include <cstdio>
#include <algorithm>
#include <cstring>
#include <limits>

#include "core/output_lock.h"

namespace nimble::mcap {
namespace {

constexpr char kMagic[8] = {'\x89', 'M', 'C', 'A', 'P', '0', '\r', '\n'};

// Record opcodes of the specification.
constexpr uint8_t kOpHeader = 0x01;
constexpr uint8_t kOpFooter = 0x02;
constexpr uint8_t kOpSchema = 0x03;
constexpr uint8_t kOpChannel = 0x04;
constexpr uint8_t kOpMessage = 0x05;
constexpr uint8_t kOpChunk = 0x06;
constexpr uint8_t kOpMessageIndex = 0x07;
constexpr uint8_t kOpChunkIndex = 0x08;
constexpr uint8_t kOpStatistics = 0x0B;
constexpr uint8_t kOpMetadata = 0x0C;
constexpr uint8_t kOpMetadataIndex = 0x0D;
constexpr uint8_t kOpSummaryOffset = 0x0E;
constexpr uint8_t kOpDataEnd = 0x0F;

// Little-endian serialisation, whatever the host's byte order.
inline void put8(std::string& out, uint8_t v) { out.push_back(static_cast<char>(v)); }
inline void put16(std::string& out, uint16_t v) {
  const char b[2] = {static_cast<char>(v), static_cast<char>(v >> 8)};
  out.append(b, 2);
}
inline void put32(std::string& out, uint32_t v) {
  const char b[4] = {static_cast<char>(v), static_cast<char>(v >> 8), static_cast<char>(v >> 16),
                     static_cast<char>(v >> 24)};
  out.append(b, 4);
}
inline void put64(std::string& out, uint64_t v) {
  char b[8];
  for (int i = 0; i < 8; ++i) b[i] = static_cast<char>(v >> (8 * i));
  out.append(b, 8);
}
/// Overwrites 8 bytes at `pos` (a length written before its record's content was known).
inline void patch64(std::string& out, std::size_t pos, uint64_t v) {
  for (int i = 0; i < 8; ++i) out[pos + i] = static_cast<char>(v >> (8 * i));
}
inline void put_string(std::string& out, const std::string& s) {
  if (s.size() > std::numeric_limits<uint32_t>::max()) throw std::invalid_argument("MCAP string longer than 4 GiB");
  put32(out, static_cast<uint32_t>(s.size()));
  out.append(s);
}
/// MCAP's Map<uint16, uint64>: its byte length (10 per entry), then each key and value.
inline void put_u16_u64_map(std::string& out, const std::vector<std::pair<uint16_t, uint64_t>>& entries) {
  put32(out, static_cast<uint32_t>(10 * entries.size()));
  for (const auto& e : entries) {
    put16(out, e.first);
    put64(out, e.second);
  }
}
inline void put_string_map(std::string& out, const std::map<std::string, std::string>& m) {
  uint64_t bytes = 0;
  for (const auto& kv : m) bytes += 8 + kv.first.size() + kv.second.size();
  if (bytes > std::numeric_limits<uint32_t>::max()) throw std::invalid_argument("MCAP map longer than 4 GiB");
  put32(out, static_cast<uint32_t>(bytes));
  for (const auto& kv : m) {
    put_string(out, kv.first);
    put_string(out, kv.second);
  }
}
/// Starts a record: opcode and a length to patch; returns the length's position.
inline std::size_t begin_record(std::string& out, uint8_t op) {
  put8(out, op);
  const std::size_t at = out.size();
  put64(out, 0);
  return at;
}
inline void end_record(std::string& out, std::size_t length_at) { patch64(out, length_at, out.size() - length_at - 8); }

uint32_t crc32_update(uint32_t crc, const void* data, std::size_t size) {
  const auto* p = static_cast<const Bytef*>(data);
  uLong c = crc;
  while (size > 0) {
    const uInt n = size > (1u << 30) ? (1u << 30) : static_cast<uInt>(size);
    c = ::crc32(c, p, n);
    p += n;
    size -= n;
  }
  return static_cast<uint32_t>(c);
}

}  // namespace

struct McapWriter::ZstdContext {
  ZSTD_CCtx* cctx = nullptr;
  ZstdContext() : cctx(ZSTD_createCCtx()) {
    if (cctx == nullptr) throw std::bad_alloc();
  }
  ~ZstdContext() { ZSTD_freeCCtx(cctx); }
  ZstdContext(const ZstdContext&) = delete;
  ZstdContext& operator=(const ZstdContext&) = delete;
};

const char* to_string(Compression c) { return c == Compression::kZstd ? "zstd" : "none"; }

Compression compression_from_string(const std::string& text) {
  if (text == "zstd") return Compression::kZstd;
  if (text == "none") return Compression::kNone;
  throw std::invalid_argument("unknown MCAP compression '" + text + "' (zstd or none)");
}

McapWriter::McapWriter(const std::string& path, WriterOptions options)
    : path_(path), part_path_(part_file_of(path)), options_(std::move(options)) {
  if (options_.chunk_size == 0) throw std::invalid_argument("MCAP chunk size must be > 0");
  if (options_.compression == Compression::kZstd) {
    if (options_.zstd_level < ZSTD_minCLevel() || options_.zstd_level > ZSTD_maxCLevel()) {
      throw std::invalid_argument("zstd level " + std::to_string(options_.zstd_level) + " out of range " +
                                  std::to_string(ZSTD_minCLevel()) + ".." + std::to_string(ZSTD_maxCLevel()));
    }
    zstd_ = std::make_unique<ZstdContext>();
    ZSTD_CCtx_setParameter(zstd_->cctx, ZSTD_c_compressionLevel, options_.zstd_level);
    ZSTD_CCtx_setParameter(zstd_->cctx, ZSTD_c_checksumFlag, 0);
  }
  // Not truncated before it is ours: another writer's part stays whole (OutputBusy names it).
  const int fd = ::open(part_path_.c_str(), O_WRONLY | O_CREAT | O_CLOEXEC, 0666);
  if (fd < 0) throw WriteError("cannot create " + part_path_ + ": " + std::strerror(errno));
  try {
    lock_open_output(fd, path_, "the MCAP file");
  } catch (...) {
    ::close(fd);
    throw;
  }
  if (::ftruncate(fd, 0) != 0 || (file_ = ::fdopen(fd, "wb")) == nullptr) {
    const int e = errno;
    ::close(fd);
    throw WriteError("cannot create " + part_path_ + ": " + std::strerror(e));
  }
  std::setvbuf(file_, nullptr, _IOFBF, 1u << 20);
  chunk_.reserve(options_.chunk_size + (64u << 10));

  std::string head(kMagic, sizeof kMagic);
  const std::size_t at = begin_record(head, kOpHeader);
  put_string(head, options_.profile);
  put_string(head, options_.library);
  end_record(head, at);
  write_out(head.data(), head.size());
}

McapWriter::~McapWriter() {
  if (file_ != nullptr) std::fclose(file_);
  if (!closed_) std::remove(part_path_.c_str());
}

void McapWriter::check_open() const {
  if (closed_ || file_ == nullptr) throw std::logic_error("MCAP writer of " + path_ + " is closed");
}

void McapWriter::fail(const std::string& what) {
  const int err = errno;
  const std::string reason = err != 0 ? std::string(": ") + std::strerror(err) : std::string();
  if (file_ != nullptr) std::fclose(file_);
  file_ = nullptr;
  std::remove(part_path_.c_str());
  throw WriteError("cannot write " + path_ + " (" + what + " of " + part_path_ + reason + ")");
}

void McapWriter::write_out(const void* data, std::size_t size) {
  errno = 0;
  if (size > 0 && std::fwrite(data, 1, size, file_) != size) fail("write");
  data_crc_ = crc32_update(data_crc_, data, size);
  offset_ += size;
}

uint16_t McapWriter::add_schema(const std::string& name, const std::string& encoding, const std::string& data) {
  check_open();
  if (schemas_.size() >= 0xFFFF) throw std::invalid_argument("more than 65535 MCAP schemas");
  schemas_.push_back({name, encoding, data});
  schema_in_chunk_.push_back(false);
  return static_cast<uint16_t>(schemas_.size());
}

uint16_t McapWriter::add_channel(uint16_t schema_id, const std::string& topic, const std::string& message_encoding,
                                 const std::map<std::string, std::string>& metadata) {
  check_open();
  if (schema_id > schemas_.size()) {
    throw std::invalid_argument("MCAP channel " + topic + ": no schema " + std::to_string(schema_id));
  }
  if (channels_.size() >= 0xFFFF) throw std::invalid_argument("more than 65535 MCAP channels");
  Channel c;
  c.schema_id = schema_id;
  c.topic = topic;
  c.message_encoding = message_encoding;
  c.metadata = metadata;
  channels_.push_back(std::move(c));
  chunk_index_.emplace_back();
  return static_cast<uint16_t>(channels_.size());
}

void McapWriter::write_schema_record(std::string& out, uint16_t id) {
  const Schema& s = schemas_[id - 1];
  const std::size_t at = begin_record(out, kOpSchema);
  put16(out, id);
  put_string(out, s.name);
  put_string(out, s.encoding);
  put_string(out, s.data);  // uint32-prefixed bytes: the same layout as a string
  end_record(out, at);
}

void McapWriter::write_channel_record(std::string& out, uint16_t id) {
  const Channel& c = channels_[id - 1];
  const std::size_t at = begin_record(out, kOpChannel);
  put16(out, id);
  put16(out, c.schema_id);
  put_string(out, c.topic);
  put_string(out, c.message_encoding);
  put_string_map(out, c.metadata);
  end_record(out, at);
}

void McapWriter::add_message(uint16_t channel_id, uint32_t sequence, uint64_t log_time_ns, uint64_t publish_time_ns,
                             const void* data, std::size_t size) {
  check_open();
  if (channel_id == 0 || channel_id > channels_.size()) {
    throw std::invalid_argument("MCAP message on unknown channel " + std::to_string(channel_id));
  }
  Channel& c = channels_[channel_id - 1];
  // A chunk is self-contained for a streaming reader: it repeats the schema and channel of
  // every message it holds, before the first of them.
  if (!c.in_chunk) {
    if (c.schema_id != 0 && !schema_in_chunk_[c.schema_id - 1]) {
      write_schema_record(chunk_, c.schema_id);
      schema_in_chunk_[c.schema_id - 1] = true;
    }
    write_channel_record(chunk_, channel_id);
    c.in_chunk = true;
  }
  auto& index = chunk_index_[channel_id - 1];
  if (index.empty()) chunk_channels_.push_back(channel_id);
  index.emplace_back(log_time_ns, chunk_.size());

  put8(chunk_, kOpMessage);
  put64(chunk_, 2 + 4 + 8 + 8 + static_cast<uint64_t>(size));
  put16(chunk_, channel_id);
  put32(chunk_, sequence);
  put64(chunk_, log_time_ns);
  put64(chunk_, publish_time_ns);
  chunk_.append(static_cast<const char*>(data), size);

  if (!chunk_has_messages_) {
    chunk_start_ = chunk_end_ = log_time_ns;
    chunk_has_messages_ = true;
  } else {
    if (log_time_ns < chunk_start_) chunk_start_ = log_time_ns;
    if (log_time_ns > chunk_end_) chunk_end_ = log_time_ns;
  }
  if (stats_.messages == 0 || log_time_ns < message_start_) message_start_ = log_time_ns;
  if (stats_.messages == 0 || log_time_ns > message_end_) message_end_ = log_time_ns;
  ++stats_.messages;
  ++c.count;
  if (chunk_.size() >= options_.chunk_size) flush_chunk();
}

void McapWriter::flush_chunk() {
  if (chunk_.empty()) return;
  const char* records = chunk_.data();
  std::size_t records_size = chunk_.size();
  const uint32_t crc = crc32_update(0, chunk_.data(), chunk_.size());
  const char* compression = "";
  if (options_.compression == Compression::kZstd) {
    compressed_.resize(ZSTD_compressBound(chunk_.size()));
    const std::size_t n =
        ZSTD_compress2(zstd_->cctx, compressed_.data(), compressed_.size(), chunk_.data(), chunk_.size());
    if (ZSTD_isError(n)) {
      errno = 0;
      fail(std::string("zstd compression: ") + ZSTD_getErrorName(n));
    }
    records = compressed_.data();
    records_size = n;
    compression = "zstd";
  }

  ChunkIndex ci;
  ci.start_time = chunk_has_messages_ ? chunk_start_ : 0;
  ci.end_time = chunk_has_messages_ ? chunk_end_ : 0;
  ci.offset = offset_;
  ci.compressed_size = records_size;
  ci.uncompressed_size = chunk_.size();

  scratch_.clear();
  const std::string comp(compression);
  put8(scratch_, kOpChunk);
  put64(scratch_, 8 + 8 + 8 + 4 + 4 + comp.size() + 8 + records_size);
  put64(scratch_, ci.start_time);
  put64(scratch_, ci.end_time);
  put64(scratch_, chunk_.size());
  put32(scratch_, crc);
  put_string(scratch_, comp);
  put64(scratch_, records_size);
  write_out(scratch_.data(), scratch_.size());
  write_out(records, records_size);
  ci.length = scratch_.size() + records_size;

  // One Message Index per channel of the chunk, right after it.
  scratch_.clear();
  const uint64_t index_start = offset_;
  for (const uint16_t id : chunk_channels_) {
    auto& entries = chunk_index_[id - 1];
    // Readers look messages up by time: each index in log-time order, even where a channel's
    // messages were added out of it (ties keep their order in the chunk).
    const auto by_time = [](const std::pair<uint64_t, uint64_t>& a, const std::pair<uint64_t, uint64_t>& b) {
      return a.first < b.first;
    };
    if (!std::is_sorted(entries.begin(), entries.end(), by_time)) {
      std::stable_sort(entries.begin(), entries.end(), by_time);
    }
    ci.message_index_offsets.emplace_back(id, index_start + scratch_.size());
    put8(scratch_, kOpMessageIndex);
    put64(scratch_, 2 + 4 + 16 * static_cast<uint64_t>(entries.size()));
    put16(scratch_, id);
    put32(scratch_, static_cast<uint32_t>(16 * entries.size()));
    for (const auto& e : entries) {
      put64(scratch_, e.first);
      put64(scratch_, e.second);
    }
    entries.clear();
  }
  write_out(scratch_.data(), scratch_.size());
  ci.message_index_length = scratch_.size();

  stats_.uncompressed_chunk_bytes += chunk_.size();
  stats_.compressed_chunk_bytes += records_size;
  ++stats_.chunks;
  chunk_indexes_.push_back(std::move(ci));

  chunk_.clear();
  chunk_channels_.clear();
  chunk_has_messages_ = false;
  for (auto& c : channels_) c.in_chunk = false;
  std::fill(schema_in_chunk_.begin(), schema_in_chunk_.end(), false);
}

void McapWriter::add_metadata(const std::string& name, const std::map<std::string, std::string>& metadata) {
  check_open();
  flush_chunk();  // a Metadata record may not sit inside a chunk
  scratch_.clear();
  const std::size_t at = begin_record(scratch_, kOpMetadata);
  put_string(scratch_, name);
  put_string_map(scratch_, metadata);
  end_record(scratch_, at);
  metadata_indexes_.push_back({offset_, scratch_.size(), name});
  write_out(scratch_.data(), scratch_.size());
}

void McapWriter::close() {
  check_open();
  flush_chunk();

  // DataEnd: the CRC of every byte before it.
  std::string out;
  {
    const std::size_t at = begin_record(out, kOpDataEnd);
    put32(out, data_crc_);
    end_record(out, at);
  }
  write_out(out.data(), out.size());

  // Summary section, grouped by opcode; the offset of each group is recorded for the summary
  // offset section.
  const uint64_t summary_start = offset_;
  std::string summary;
  struct Group {
    uint8_t op;
    uint64_t start, length;
  };
  std::vector<Group> groups;
  auto group = [&](uint8_t op, std::size_t begin) {
    if (summary.size() > begin) groups.push_back({op, summary_start + begin, summary.size() - begin});
  };

  std::size_t begin = summary.size();
  for (std::size_t i = 0; i < schemas_.size(); ++i) write_schema_record(summary, static_cast<uint16_t>(i + 1));
  group(kOpSchema, begin);

  begin = summary.size();
  for (std::size_t i = 0; i < channels_.size(); ++i) write_channel_record(summary, static_cast<uint16_t>(i + 1));
  group(kOpChannel, begin);

  begin = summary.size();
  {
    const std::size_t at = begin_record(summary, kOpStatistics);
    put64(summary, stats_.messages);
    put16(summary, static_cast<uint16_t>(schemas_.size()));
    put32(summary, static_cast<uint32_t>(channels_.size()));
    put32(summary, 0);  // attachments
    put32(summary, static_cast<uint32_t>(metadata_indexes_.size()));
    put32(summary, static_cast<uint32_t>(chunk_indexes_.size()));
    put64(summary, stats_.messages > 0 ? message_start_ : 0);
    put64(summary, stats_.messages > 0 ? message_end_ : 0);
    std::vector<std::pair<uint16_t, uint64_t>> channel_counts;
    for (std::size_t i = 0; i < channels_.size(); ++i) {
      channel_counts.emplace_back(static_cast<uint16_t>(i + 1), channels_[i].count);
    }
    put_u16_u64_map(summary, channel_counts);
    end_record(summary, at);
  }
  group(kOpStatistics, begin);

  begin = summary.size();
  for (const ChunkIndex& ci : chunk_indexes_) {
    const std::size_t at = begin_record(summary, kOpChunkIndex);
    put64(summary, ci.start_time);
    put64(summary, ci.end_time);
    put64(summary, ci.offset);
    put64(summary, ci.length);
    put_u16_u64_map(summary, ci.message_index_offsets);
    put64(summary, ci.message_index_length);
    put_string(summary, options_.compression == Compression::kZstd ? "zstd" : "");
    put64(summary, ci.compressed_size);
    put64(summary, ci.uncompressed_size);
    end_record(summary, at);
  }
  group(kOpChunkIndex, begin);

  begin = summary.size();
  for (const MetadataIndex& mi : metadata_indexes_) {
    const std::size_t at = begin_record(summary, kOpMetadataIndex);
    put64(summary, mi.offset);
    put64(summary, mi.length);
    put_string(summary, mi.name);
    end_record(summary, at);
  }
  group(kOpMetadataIndex, begin);

  const uint64_t summary_offset_start = summary_start + summary.size();
  for (const Group& g : groups) {
    const std::size_t at = begin_record(summary, kOpSummaryOffset);
    put8(summary, g.op);
    put64(summary, g.start);
    put64(summary, g.length);
    end_record(summary, at);
  }

  // Footer: the summary CRC covers the summary, the summary offsets and the footer up to its
  // summary_offset_start field.
  put8(summary, kOpFooter);
  put64(summary, 8 + 8 + 4);
  put64(summary, summary_start);
  put64(summary, summary_offset_start);
  put32(summary, crc32_update(0, summary.data(), summary.size()));
  summary.append(kMagic, sizeof kMagic);
  write_out(summary.data(), summary.size());

  errno = 0;
  if (std::fflush(file_) != 0) fail("flush");
  if (::fsync(::fileno(file_)) != 0 && errno != EINVAL) fail("fsync");
  errno = 0;
  const int rc = std::fclose(file_);
  file_ = nullptr;
  if (rc != 0) fail("close");
  errno = 0;
  if (std::rename(part_path_.c_str(), path_.c_str()) != 0) {
    fail("rename to " + path_);
  }
  closed_ = true;
  stats_.bytes = offset_;
}

}  // namespace nimble::mcap
