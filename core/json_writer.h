#pragma once
/// Streaming JSON writer for machine-readable command output, over nlohmann::json (Debian's
/// nlohmann-json3-dev): the callers build objects and arrays in order, the library does the
/// escaping and the number formatting (shortest text that reads back to the same double).
/// Keys keep the order they were written in; non-finite numbers become null; bytes that are not
/// UTF-8 are replaced by U+FFFD instead of failing.

#include <memory>
#include <string>
#include <vector>

namespace nimble {

class JsonWriter {
 public:
  JsonWriter();
  ~JsonWriter();
  JsonWriter(const JsonWriter&) = delete;
  JsonWriter& operator=(const JsonWriter&) = delete;

  JsonWriter& begin_object();
  JsonWriter& end_object();
  JsonWriter& begin_array();
  JsonWriter& end_array();
  /// Key of the next value inside an object.
  JsonWriter& key(const std::string& k);
  JsonWriter& value(double x);
  JsonWriter& value(long long x);
  JsonWriter& value(int x) { return value(static_cast<long long>(x)); }
  JsonWriter& value(bool b);
  JsonWriter& value(const std::string& s);
  JsonWriter& value(const char* s) { return value(std::string(s)); }
  JsonWriter& null();
  JsonWriter& array(const std::vector<double>& xs);
  JsonWriter& array(const std::vector<std::string>& xs);

  /// The document written so far, compact (one line).
  std::string str() const;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

/// JSON string literal of `s` with quotes and escapes.
std::string json_quote(const std::string& s);

}  // namespace nimble
