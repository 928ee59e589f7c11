#pragma once
/// Minimal streaming JSON writer for machine-readable command output.
/// Numbers are written with 17 significant digits (round-trip exact);
/// non-finite numbers become null.

#include <string>
#include <vector>

namespace nimble {

class JsonWriter {
 public:
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

  const std::string& str() const { return out_; }

 private:
  void before_value();
  std::string out_;
  std::vector<bool> first_;  // per open container: no element written yet
  bool after_key_ = false;
};

/// JSON string literal of `s` with quotes and escapes.
std::string json_quote(const std::string& s);

}  // namespace nimble
