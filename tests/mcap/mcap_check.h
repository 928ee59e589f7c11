#pragma once
/// An independent, minimal MCAP reader for the tests: parses a whole file by the public
/// specification and checks its structure (magic, every record's length, chunk CRCs and
/// sizes, message indexes, the data section and summary CRCs, statistics, chunk and metadata
/// indexes, summary offsets). It shares no code with mcap/mcap_writer.cc. Every problem is a
/// string in `McapFile::problems`; the messages, channels and schemas it found are returned
/// for the tests to compare with what they wrote.

#include <zlib.h>
#include <zstd.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <map>
#include <set>
#include <sstream>
#include <string>
#include <vector>

namespace nimble::test::mcap_check {

struct Schema {
  std::string name, encoding, data;
};
struct Channel {
  uint16_t schema_id = 0;
  std::string topic, message_encoding;
  std::map<std::string, std::string> metadata;
};
struct Message {
  uint16_t channel_id = 0;
  uint32_t sequence = 0;
  uint64_t log_time = 0, publish_time = 0;
  std::string data;
};
struct Statistics {
  uint64_t message_count = 0;
  uint16_t schema_count = 0;
  uint32_t channel_count = 0, attachment_count = 0, metadata_count = 0, chunk_count = 0;
  uint64_t start = 0, end = 0;
  std::map<uint16_t, uint64_t> channel_counts;
};

struct McapFile {
  std::vector<std::string> problems;
  std::string profile, library;
  std::map<uint16_t, Schema> schemas;    ///< from the summary
  std::map<uint16_t, Channel> channels;  ///< from the summary
  std::vector<Message> messages;         ///< in file order
  Statistics statistics;
  bool has_statistics = false;
  std::vector<std::string> compressions;  ///< per chunk
  std::map<std::string, std::map<std::string, std::string>> metadata;
  uint64_t chunk_count = 0;
  uint64_t max_uncompressed_chunk = 0;
};

/// Reads fixed fields from a byte string, noting a read past its end.
class Cursor {
 public:
  Cursor(const std::string& s, std::size_t pos, std::size_t end) : s_(s), pos_(pos), end_(end) {}
  uint64_t u(int bytes) {
    if (pos_ + bytes > end_) {
      bad_ = true;
      return 0;
    }
    uint64_t v = 0;
    for (int i = 0; i < bytes; ++i) v |= static_cast<uint64_t>(static_cast<uint8_t>(s_[pos_ + i])) << (8 * i);
    pos_ += bytes;
    return v;
  }
  std::string bytes(uint64_t n) {
    if (pos_ + n > end_) {
      bad_ = true;
      return {};
    }
    std::string out = s_.substr(pos_, n);
    pos_ += n;
    return out;
  }
  std::string str() { return bytes(u(4)); }
  std::map<std::string, std::string> string_map() {
    const uint64_t len = u(4);
    const std::size_t stop = pos_ + len;
    std::map<std::string, std::string> m;
    while (!bad_ && pos_ < stop) {
      std::string k = str();
      m[k] = str();
    }
    if (pos_ != stop) bad_ = true;
    return m;
  }
  std::size_t pos() const { return pos_; }
  std::size_t end() const { return end_; }
  bool bad() const { return bad_; }

 private:
  const std::string& s_;
  std::size_t pos_, end_;
  bool bad_ = false;
};

inline uint32_t crc(const std::string& s, std::size_t begin, std::size_t end) {
  return static_cast<uint32_t>(
      ::crc32(0, reinterpret_cast<const Bytef*>(s.data() + begin), static_cast<uInt>(end - begin)));
}

inline std::string slurp_binary(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

struct Record {
  uint8_t op = 0;
  std::size_t offset = 0;  ///< of the opcode
  std::size_t body = 0;    ///< of the content
  uint64_t length = 0;     ///< content length
  std::size_t total() const { return 9 + length; }
};

/// Splits s[begin, end) into records; a record running past `end` is a problem.
inline std::vector<Record> split_records(const std::string& s, std::size_t begin, std::size_t end,
                                         std::vector<std::string>& problems, const std::string& where) {
  std::vector<Record> out;
  std::size_t pos = begin;
  while (pos < end) {
    if (pos + 9 > end) {
      problems.push_back(where + ": truncated record header at " + std::to_string(pos));
      break;
    }
    Record r;
    r.op = static_cast<uint8_t>(s[pos]);
    r.offset = pos;
    r.body = pos + 9;
    Cursor c(s, pos + 1, end);
    r.length = c.u(8);
    if (r.body + r.length > end) {
      problems.push_back(where + ": record 0x" + std::to_string(r.op) + " at " + std::to_string(pos) + " has length " +
                         std::to_string(r.length) + " past the end");
      break;
    }
    out.push_back(r);
    pos = r.body + r.length;
  }
  return out;
}

inline McapFile check(const std::string& file) {
  McapFile f;
  auto& P = f.problems;
  static const std::string kMagic("\x89MCAP0\r\n", 8);
  if (file.size() < 16 + 9 + 20 || file.compare(0, 8, kMagic) != 0 || file.compare(file.size() - 8, 8, kMagic) != 0) {
    P.push_back("no MCAP magic at both ends");
    return f;
  }
  const std::size_t end = file.size() - 8;
  const std::vector<Record> all = split_records(file, 8, end, P, "file");
  if (!P.empty()) return f;
  if (all.empty() || all.front().op != 0x01) P.push_back("first record is not a Header");
  if (all.empty() || all.back().op != 0x02 || all.back().length != 20)
    P.push_back("last record is not a Footer of 20 bytes");
  if (!P.empty()) return f;
  {
    Cursor c(file, all.front().body, all.front().body + all.front().length);
    f.profile = c.str();
    f.library = c.str();
    if (c.bad()) P.push_back("Header fields run past its length");
  }
  // Footer.
  const Record& footer = all.back();
  Cursor fc(file, footer.body, footer.body + footer.length);
  const uint64_t summary_start = fc.u(8), summary_offset_start = fc.u(8);
  const uint32_t summary_crc = static_cast<uint32_t>(fc.u(4));

  // Data section: up to DataEnd.
  std::size_t data_end_index = 0;
  for (std::size_t i = 0; i < all.size(); ++i) {
    if (all[i].op == 0x0F) {
      data_end_index = i;
      break;
    }
  }
  if (data_end_index == 0) {
    P.push_back("no DataEnd record");
    return f;
  }
  {
    Cursor c(file, all[data_end_index].body, all[data_end_index].body + all[data_end_index].length);
    const uint32_t want = static_cast<uint32_t>(c.u(4));
    if (want != crc(file, 0, all[data_end_index].offset)) P.push_back("data section CRC does not match");
  }
  const std::size_t summary_at = all[data_end_index].offset + all[data_end_index].total();
  if (summary_start != summary_at) {
    P.push_back("footer summary_start " + std::to_string(summary_start) + " is not the record after DataEnd (" +
                std::to_string(summary_at) + ")");
  }
  if (summary_crc != crc(file, summary_at, footer.body + 16)) P.push_back("summary CRC does not match");

  // Chunks and message indexes, with what the chunk index must say of each.
  struct SeenChunk {
    uint64_t offset, length, start, end, compressed, uncompressed;
    std::string compression;
    std::map<uint16_t, uint64_t> index_offsets;
    uint64_t index_length = 0;
  };
  std::vector<SeenChunk> seen_chunks;
  std::map<uint64_t, std::string> metadata_at;  // offset -> name
  std::map<uint16_t, Channel> data_channels;
  std::map<uint16_t, Schema> data_schemas;
  for (std::size_t i = 1; i < data_end_index; ++i) {
    const Record& r = all[i];
    if (r.op == 0x0C) {
      Cursor c(file, r.body, r.body + r.length);
      const std::string name = c.str();
      f.metadata[name] = c.string_map();
      if (c.bad() || c.pos() != c.end()) P.push_back("Metadata record fields do not fill its length");
      metadata_at[r.offset] = name;
      continue;
    }
    if (r.op == 0x07) {
      P.push_back("Message Index at " + std::to_string(r.offset) + " not after a chunk");
      continue;
    }
    if (r.op != 0x06) {
      P.push_back("unexpected record 0x" + std::to_string(r.op) + " in the data section");
      continue;
    }
    ++f.chunk_count;
    Cursor c(file, r.body, r.body + r.length);
    SeenChunk sc{};
    sc.offset = r.offset;
    sc.length = r.total();
    sc.start = c.u(8);
    sc.end = c.u(8);
    sc.uncompressed = c.u(8);
    const uint32_t chunk_crc = static_cast<uint32_t>(c.u(4));
    sc.compression = c.str();
    sc.compressed = c.u(8);
    if (c.bad() || c.pos() + sc.compressed != c.end()) {
      P.push_back("chunk at " + std::to_string(r.offset) + ": records length does not fill the record");
      continue;
    }
    f.compressions.push_back(sc.compression);
    if (sc.uncompressed > f.max_uncompressed_chunk) f.max_uncompressed_chunk = sc.uncompressed;
    std::string records;
    if (sc.compression.empty()) {
      records = file.substr(c.pos(), sc.compressed);
    } else if (sc.compression == "zstd") {
      records.resize(sc.uncompressed);
      const std::size_t n = ZSTD_decompress(records.data(), records.size(), file.data() + c.pos(), sc.compressed);
      if (ZSTD_isError(n) || n != sc.uncompressed) {
        P.push_back("chunk at " + std::to_string(r.offset) + ": zstd does not give uncompressed_size bytes");
        continue;
      }
    } else {
      P.push_back("unknown compression " + sc.compression);
      continue;
    }
    if (records.size() != sc.uncompressed) P.push_back("chunk uncompressed_size does not match");
    if (crc(records, 0, records.size()) != chunk_crc)
      P.push_back("chunk at " + std::to_string(r.offset) + ": CRC mismatch");
    std::vector<std::string> inner_problems;
    const std::vector<Record> inner = split_records(records, 0, records.size(), inner_problems, "chunk");
    for (auto& p : inner_problems) P.push_back(p);
    std::map<uint64_t, Message> by_offset;
    uint64_t lo = UINT64_MAX, hi = 0;
    for (const Record& ir : inner) {
      Cursor ic(records, ir.body, ir.body + ir.length);
      if (ir.op == 0x03) {
        const uint16_t id = static_cast<uint16_t>(ic.u(2));
        Schema s;
        s.name = ic.str();
        s.encoding = ic.str();
        s.data = ic.str();
        data_schemas[id] = s;
      } else if (ir.op == 0x04) {
        const uint16_t id = static_cast<uint16_t>(ic.u(2));
        Channel ch;
        ch.schema_id = static_cast<uint16_t>(ic.u(2));
        ch.topic = ic.str();
        ch.message_encoding = ic.str();
        ch.metadata = ic.string_map();
        if (ch.schema_id != 0 && !data_schemas.count(ch.schema_id)) P.push_back("channel before its schema");
        data_channels[id] = ch;
      } else if (ir.op == 0x05) {
        Message m;
        m.channel_id = static_cast<uint16_t>(ic.u(2));
        m.sequence = static_cast<uint32_t>(ic.u(4));
        m.log_time = ic.u(8);
        m.publish_time = ic.u(8);
        m.data = ic.bytes(ic.end() - ic.pos());
        if (!data_channels.count(m.channel_id)) P.push_back("message before its channel in the stream");
        lo = std::min(lo, m.log_time);
        hi = std::max(hi, m.log_time);
        by_offset[ir.offset] = m;
        f.messages.push_back(m);
      } else {
        P.push_back("unexpected record in a chunk");
      }
      if (ic.bad() || (ir.op != 0x05 && ic.pos() != ic.end()))
        P.push_back("chunk record fields do not fill its length");
    }
    if (!by_offset.empty() && (sc.start != lo || sc.end != hi))
      P.push_back("chunk start/end times are not its messages'");
    // The Message Index records right after the chunk.
    std::set<uint64_t> indexed;
    std::size_t j = i + 1;
    const std::size_t first_index = j < all.size() ? all[j].offset : 0;
    for (; j < data_end_index && all[j].op == 0x07; ++j) {
      const Record& mr = all[j];
      Cursor mc(file, mr.body, mr.body + mr.length);
      const uint16_t id = static_cast<uint16_t>(mc.u(2));
      sc.index_offsets[id] = mr.offset;
      const uint64_t bytes = mc.u(4);
      if (bytes % 16 != 0 || mc.pos() + bytes != mc.end()) P.push_back("message index array length wrong");
      uint64_t previous = 0;
      for (uint64_t k = 0; k < bytes / 16; ++k) {
        const uint64_t t = mc.u(8), off = mc.u(8);
        const auto it = by_offset.find(off);
        if (it == by_offset.end()) {
          P.push_back("message index entry points at no message record");
          continue;
        }
        if (it->second.channel_id != id || it->second.log_time != t)
          P.push_back("message index entry names another message");
        if (k > 0 && t < previous) P.push_back("message index not in log-time order");
        previous = t;
        indexed.insert(off);
      }
    }
    sc.index_length = (j < all.size() ? all[j].offset : 0) - first_index;
    if (indexed.size() != by_offset.size()) P.push_back("a message of a chunk is in no message index");
    i = j - 1;
    seen_chunks.push_back(sc);
  }

  // Summary section: records up to the summary offset section, grouped by opcode.
  const std::size_t summary_end = summary_offset_start != 0 ? summary_offset_start : footer.offset;
  std::vector<Record> summary, offsets;
  for (std::size_t i = data_end_index + 1; i + 1 < all.size(); ++i) {
    (all[i].offset < summary_end ? summary : offsets).push_back(all[i]);
  }
  std::map<uint8_t, std::pair<uint64_t, uint64_t>> groups;  // op -> (start, end)
  for (std::size_t i = 0; i < summary.size(); ++i) {
    const Record& r = summary[i];
    auto it = groups.find(r.op);
    if (it == groups.end()) {
      groups[r.op] = {r.offset, r.offset + r.total()};
    } else {
      if (it->second.second != r.offset)
        P.push_back("summary records of opcode " + std::to_string(r.op) + " not grouped");
      it->second.second = r.offset + r.total();
    }
    Cursor c(file, r.body, r.body + r.length);
    if (r.op == 0x03) {
      const uint16_t id = static_cast<uint16_t>(c.u(2));
      Schema s;
      s.name = c.str();
      s.encoding = c.str();
      s.data = c.str();
      f.schemas[id] = s;
    } else if (r.op == 0x04) {
      const uint16_t id = static_cast<uint16_t>(c.u(2));
      Channel ch;
      ch.schema_id = static_cast<uint16_t>(c.u(2));
      ch.topic = c.str();
      ch.message_encoding = c.str();
      ch.metadata = c.string_map();
      f.channels[id] = ch;
    } else if (r.op == 0x0B) {
      if (f.has_statistics) P.push_back("more than one Statistics record");
      f.has_statistics = true;
      Statistics& s = f.statistics;
      s.message_count = c.u(8);
      s.schema_count = static_cast<uint16_t>(c.u(2));
      s.channel_count = static_cast<uint32_t>(c.u(4));
      s.attachment_count = static_cast<uint32_t>(c.u(4));
      s.metadata_count = static_cast<uint32_t>(c.u(4));
      s.chunk_count = static_cast<uint32_t>(c.u(4));
      s.start = c.u(8);
      s.end = c.u(8);
      const uint64_t bytes = c.u(4);
      for (uint64_t k = 0; k < bytes / 10; ++k) {
        const uint16_t id = static_cast<uint16_t>(c.u(2));
        s.channel_counts[id] = c.u(8);
      }
      for (const auto& kv : s.channel_counts) {
        if (!f.channels.count(kv.first)) P.push_back("statistics name a channel not in the summary before it");
      }
    } else if (r.op == 0x08) {
      const uint64_t start = c.u(8), stop = c.u(8), offset = c.u(8), length = c.u(8);
      std::map<uint16_t, uint64_t> index_offsets;
      const uint64_t bytes = c.u(4);
      for (uint64_t k = 0; k < bytes / 10; ++k) {
        const uint16_t id = static_cast<uint16_t>(c.u(2));
        index_offsets[id] = c.u(8);
      }
      const uint64_t index_length = c.u(8);
      const std::string compression = c.str();
      const uint64_t compressed = c.u(8), uncompressed = c.u(8);
      bool found = false;
      for (const SeenChunk& sc : seen_chunks) {
        if (sc.offset != offset) continue;
        found = true;
        if (sc.length != length) P.push_back("chunk index length wrong");
        if (sc.start != start || sc.end != stop) P.push_back("chunk index times wrong");
        if (sc.index_offsets != index_offsets) P.push_back("chunk index message index offsets wrong");
        if (sc.index_length != index_length) P.push_back("chunk index message index length wrong");
        if (sc.compression != compression) P.push_back("chunk index compression wrong");
        if (sc.compressed != compressed || sc.uncompressed != uncompressed) P.push_back("chunk index sizes wrong");
      }
      if (!found) P.push_back("chunk index points at no chunk");
    } else if (r.op == 0x0D) {
      const uint64_t offset = c.u(8), length = c.u(8);
      const std::string name = c.str();
      const auto it = metadata_at.find(offset);
      if (it == metadata_at.end() || it->second != name)
        P.push_back("metadata index points at no metadata record " + name);
      for (const Record& a : all) {
        if (a.offset == offset && a.total() != length) P.push_back("metadata index length wrong");
      }
    } else {
      P.push_back("unexpected record in the summary");
    }
    if (c.bad() || c.pos() != c.end())
      P.push_back("summary record 0x" + std::to_string(r.op) + " fields do not fill its length");
  }
  if (!summary.empty() && summary.front().offset != summary_start)
    P.push_back("summary does not start at summary_start");
  // Summary offsets: one per group, pointing at it exactly.
  std::set<uint8_t> offset_groups;
  for (const Record& r : offsets) {
    if (r.op != 0x0E) {
      P.push_back("non-Summary-Offset record in the summary offset section");
      continue;
    }
    Cursor c(file, r.body, r.body + r.length);
    const uint8_t op = static_cast<uint8_t>(c.u(1));
    const uint64_t start = c.u(8), length = c.u(8);
    offset_groups.insert(op);
    const auto it = groups.find(op);
    if (it == groups.end() || it->second.first != start || it->second.second - it->second.first != length) {
      P.push_back("summary offset of group " + std::to_string(op) + " does not point at it");
    }
  }
  if (!offsets.empty() && offsets.front().offset != summary_offset_start)
    P.push_back("summary offsets not at summary_offset_start");
  for (const auto& g : groups) {
    if (!offset_groups.count(g.first))
      P.push_back("summary group " + std::to_string(g.first) + " has no summary offset");
  }
  // Summary against the data.
  if (seen_chunks.size() != f.chunk_count) P.push_back("chunks not all seen");
  std::size_t chunk_index_count = 0;
  for (const Record& r : summary) chunk_index_count += r.op == 0x08;
  if (chunk_index_count != seen_chunks.size()) P.push_back("not one chunk index per chunk");
  std::size_t metadata_index_count = 0;
  for (const Record& r : summary) metadata_index_count += r.op == 0x0D;
  if (metadata_index_count != metadata_at.size()) P.push_back("not one metadata index per metadata record");
  for (const auto& kv : data_channels) {
    const auto it = f.channels.find(kv.first);
    if (it == f.channels.end() || it->second.topic != kv.second.topic || it->second.schema_id != kv.second.schema_id ||
        it->second.message_encoding != kv.second.message_encoding || it->second.metadata != kv.second.metadata) {
      P.push_back("channel " + std::to_string(kv.first) + " differs between data and summary");
    }
  }
  for (const auto& kv : data_schemas) {
    const auto it = f.schemas.find(kv.first);
    if (it == f.schemas.end() || it->second.name != kv.second.name || it->second.data != kv.second.data ||
        it->second.encoding != kv.second.encoding) {
      P.push_back("schema " + std::to_string(kv.first) + " differs between data and summary");
    }
  }
  if (f.has_statistics) {
    const Statistics& s = f.statistics;
    if (s.message_count != f.messages.size()) P.push_back("statistics message count wrong");
    if (s.chunk_count != seen_chunks.size()) P.push_back("statistics chunk count wrong");
    if (s.channel_count != f.channels.size() || s.schema_count != f.schemas.size())
      P.push_back("statistics channel/schema count wrong");
    if (s.metadata_count != metadata_at.size()) P.push_back("statistics metadata count wrong");
    std::map<uint16_t, uint64_t> counts;
    uint64_t lo = UINT64_MAX, hi = 0;
    for (const Message& m : f.messages) {
      ++counts[m.channel_id];
      lo = std::min(lo, m.log_time);
      hi = std::max(hi, m.log_time);
    }
    for (const auto& kv : s.channel_counts) {
      if (kv.second != (counts.count(kv.first) ? counts[kv.first] : 0)) P.push_back("statistics channel count wrong");
    }
    if (!f.messages.empty() && (s.start != lo || s.end != hi)) P.push_back("statistics start/end wrong");
  }
  return f;
}

/// All problems, one a line ("" if none).
inline std::string problems_text(const McapFile& f) {
  std::ostringstream out;
  for (const auto& p : f.problems) out << p << "\n";
  return out.str();
}

}  // namespace nimble::test::mcap_check
