/// An encoded LCM message as JSON, by walking its bytes against its parsed type.

#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>

#include "lcmjson/lcm_json.h"
#include "transport/clock.h"

namespace nimble::lcmjson {

namespace {

enum class Kind { kInt8, kInt16, kInt32, kInt64, kByte, kBoolean, kFloat, kDouble, kString };

Kind kind_of(const std::string& type) {
  switch (type[0]) {
    case 'i':
      return type[3] == '8'   ? Kind::kInt8
             : type[3] == '1' ? Kind::kInt16
             : type[3] == '3' ? Kind::kInt32
                              : Kind::kInt64;
    case 'b': return type[1] == 'y' ? Kind::kByte : Kind::kBoolean;
    case 'f': return Kind::kFloat;
    case 'd': return Kind::kDouble;
    default: return Kind::kString;
  }
}

/// Big-endian reader over the message's bytes; every read checks the length first.
class Reader {
 public:
  Reader(const uint8_t* data, std::size_t size) : p_(data), end_(data + size) {}
  bool has(std::size_t n) const { return static_cast<std::size_t>(end_ - p_) >= n; }
  std::size_t left() const { return static_cast<std::size_t>(end_ - p_); }
  uint64_t be(int n) {
    uint64_t v = 0;
    for (int i = 0; i < n; ++i) v = (v << 8) | p_[i];
    p_ += n;
    return v;
  }
  const uint8_t* take(std::size_t n) {
    const uint8_t* at = p_;
    p_ += n;
    return at;
  }

 private:
  const uint8_t* p_;
  const uint8_t* end_;
};

void append_int(std::string* out, int64_t v) {
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out->append(buf, r.ptr);
}

template <typename F>
void append_real(std::string* out, F v) {
  if (!std::isfinite(v)) {
    out->append("null");
    return;
  }
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, v);
  out->append(buf, r.ptr);
}

/// Appends `n` bytes as a JSON string. Bytes that are not UTF-8 are written as \u00XX (their
/// Latin-1 reading), so the JSON stays valid and nothing is lost.
void append_string(std::string* out, const uint8_t* s, std::size_t n) {
  static const char kHex[] = "0123456789abcdef";
  out->push_back('"');
  std::size_t i = 0;
  while (i < n) {
    const uint8_t c = s[i];
    if (c >= 0x20 && c < 0x80 && c != '"' && c != '\\') {
      out->push_back(static_cast<char>(c));
      ++i;
      continue;
    }
    if (c == '"' || c == '\\') {
      out->push_back('\\');
      out->push_back(static_cast<char>(c));
      ++i;
      continue;
    }
    if (c >= 0x80) {
      // A well-formed UTF-8 sequence passes as it is.
      const int len = (c & 0xE0) == 0xC0 ? 2 : (c & 0xF0) == 0xE0 ? 3 : (c & 0xF8) == 0xF0 ? 4 : 0;
      bool ok = len > 0 && i + static_cast<std::size_t>(len) <= n && c >= 0xC2 && c <= 0xF4;
      for (int k = 1; ok && k < len; ++k) ok = (s[i + static_cast<std::size_t>(k)] & 0xC0) == 0x80;
      if (ok && len == 3) {
        const uint32_t cp = ((c & 0x0Fu) << 12) | ((s[i + 1] & 0x3Fu) << 6) | (s[i + 2] & 0x3Fu);
        ok = cp >= 0x800 && (cp < 0xD800 || cp > 0xDFFF);
      } else if (ok && len == 4) {
        const uint32_t cp =
            ((c & 0x07u) << 18) | ((s[i + 1] & 0x3Fu) << 12) | ((s[i + 2] & 0x3Fu) << 6) | (s[i + 3] & 0x3Fu);
        ok = cp >= 0x10000 && cp <= 0x10FFFF;
      }
      if (ok) {
        out->append(reinterpret_cast<const char*>(s + i), static_cast<std::size_t>(len));
        i += static_cast<std::size_t>(len);
        continue;
      }
    }
    out->append("\\u00");
    out->push_back(kHex[c >> 4]);
    out->push_back(kHex[c & 15]);
    ++i;
  }
  out->push_back('"');
}

std::size_t fixed_size(Kind k) {
  switch (k) {
    case Kind::kInt8:
    case Kind::kByte:
    case Kind::kBoolean: return 1;
    case Kind::kInt16: return 2;
    case Kind::kInt32:
    case Kind::kFloat: return 4;
    case Kind::kInt64:
    case Kind::kDouble: return 8;
    case Kind::kString: return 0;
  }
  return 0;
}

}  // namespace

std::string to_json(const LcmStruct& type, const void* data, std::size_t size, JsonMessage* out) {
  out->json.clear();
  out->rig_time_us = -1;
  Reader in(static_cast<const uint8_t*>(data), size);
  if (!in.has(8)) return "shorter than a fingerprint (" + std::to_string(size) + " bytes)";
  if (in.be(8) != type.fingerprint) return "not a " + type.full_name() + " (another fingerprint)";

  // Values of the scalar integer fields, for variable array sizes.
  int64_t scalars[64];
  const std::size_t nfields = type.fields.size();
  std::string& json = out->json;
  json.push_back('{');
  for (std::size_t fi = 0; fi < nfields; ++fi) {
    const LcmField& f = type.fields[fi];
    const Kind kind = kind_of(f.type);
    if (fi) json.push_back(',');
    json.push_back('"');
    json.append(f.name);
    json.append("\":");
    std::size_t count = 1;
    for (const auto& d : f.dims) {
      int64_t n = -1;
      if (d[0] >= '0' && d[0] <= '9') {
        n = std::stoll(d);
      } else {
        for (std::size_t k = 0; k < fi && k < 64; ++k) {
          if (type.fields[k].name == d) n = scalars[k];
        }
      }
      if (n < 0) return "field " + f.name + ": array size " + d + " is " + std::to_string(n);
      if (n > static_cast<int64_t>(size))
        return "field " + f.name + ": array size " + std::to_string(n) + " larger than the message";
      count *= static_cast<std::size_t>(n);
    }
    const bool array = !f.dims.empty();
    const std::size_t width = fixed_size(kind);
    if (width && !in.has(width * count)) return "truncated in field " + f.name;
    if (array) json.push_back('[');
    for (std::size_t i = 0; i < count; ++i) {
      if (i) json.push_back(',');
      switch (kind) {
        case Kind::kInt8: {
          const int64_t v = static_cast<int8_t>(in.be(1));
          if (!array && fi < 64) scalars[fi] = v;
          append_int(&json, v);
          break;
        }
        case Kind::kByte: append_int(&json, static_cast<int64_t>(in.be(1))); break;
        case Kind::kInt16: {
          const int64_t v = static_cast<int16_t>(in.be(2));
          if (!array && fi < 64) scalars[fi] = v;
          append_int(&json, v);
          break;
        }
        case Kind::kInt32: {
          const int64_t v = static_cast<int32_t>(in.be(4));
          if (!array && fi < 64) scalars[fi] = v;
          append_int(&json, v);
          break;
        }
        case Kind::kInt64: {
          const int64_t v = static_cast<int64_t>(in.be(8));
          if (!array && fi < 64) scalars[fi] = v;
          if (static_cast<int>(fi) == type.rig_time_field && transport::plausible_sim_utime(v)) out->rig_time_us = v;
          append_int(&json, v);
          break;
        }
        case Kind::kBoolean: {
          // As LCM's decoder takes it: any byte but 0 is true.
          json.append(in.be(1) ? "true" : "false");
          break;
        }
        case Kind::kFloat: {
          const uint32_t bits = static_cast<uint32_t>(in.be(4));
          float v;
          std::memcpy(&v, &bits, sizeof v);
          append_real(&json, v);
          break;
        }
        case Kind::kDouble: {
          const uint64_t bits = in.be(8);
          double v;
          std::memcpy(&v, &bits, sizeof v);
          append_real(&json, v);
          break;
        }
        case Kind::kString: {
          if (!in.has(4)) return "truncated in field " + f.name;
          const int64_t len = static_cast<int32_t>(in.be(4));
          if (len < 1 || static_cast<std::size_t>(len) > in.left()) {
            return "field " + f.name + ": string length " + std::to_string(len) + " with " + std::to_string(in.left()) +
                   " bytes left";
          }
          const uint8_t* s = in.take(static_cast<std::size_t>(len));
          if (s[len - 1] != 0) return "field " + f.name + ": a string without its terminating NUL";
          if (std::memchr(s, 0, static_cast<std::size_t>(len - 1)) != nullptr)
            return "field " + f.name + ": a string with a NUL inside";
          append_string(&json, s, static_cast<std::size_t>(len - 1));
          break;
        }
      }
    }
    if (array) json.push_back(']');
  }
  json.push_back('}');
  if (in.left() != 0) return std::to_string(in.left()) + " bytes left over after a " + type.full_name();
  return "";
}

int64_t rig_time_us(const LcmStruct& type, const void* data, std::size_t size) {
  if (type.rig_time_field < 0 || size < 8) return -1;
  if (Reader(static_cast<const uint8_t*>(data), 8).be(8) != type.fingerprint) return -1;
  std::size_t offset = 8;
  for (int i = 0; i < type.rig_time_field; ++i) {
    const LcmField& f = type.fields[static_cast<std::size_t>(i)];
    const std::size_t width = fixed_size(kind_of(f.type));
    if (width == 0 || !f.dims.empty()) {
      JsonMessage m;  // a field of variable size before it: decode the whole message
      return to_json(type, data, size, &m).empty() ? m.rig_time_us : -1;
    }
    offset += width;
  }
  if (size < offset + 8) return -1;
  Reader in(static_cast<const uint8_t*>(data) + offset, 8);
  const int64_t t = static_cast<int64_t>(in.be(8));
  return transport::plausible_sim_utime(t) ? t : -1;
}

}  // namespace nimble::lcmjson
