#include "core/json_writer.h"

#include <cmath>
#include <stdexcept>

#include "core/json_line.h"

namespace nimble {

using Json = OrderedJson;

struct JsonWriter::Impl {
  Json root;
  std::vector<Json*> open;  ///< the containers begun and not ended, outermost first
  std::string key;
  bool has_key = false;

  /// Places `v` where the document is: the root, the next element of the open array, or the
  /// value of the pending key. Returns where it went (a new container is opened there).
  Json* put(Json v) {
    if (open.empty()) {
      root = std::move(v);
      return &root;
    }
    Json& top = *open.back();
    if (top.is_object()) {
      if (!has_key) throw std::logic_error("JsonWriter: a value inside an object needs a key first");
      has_key = false;
      Json& slot = top[key];
      slot = std::move(v);
      return &slot;
    }
    top.push_back(std::move(v));
    return &top.back();
  }
};

JsonWriter::JsonWriter() : impl_(std::make_unique<Impl>()) {}
JsonWriter::~JsonWriter() = default;

JsonWriter& JsonWriter::begin_object() {
  impl_->open.push_back(impl_->put(Json::object()));
  return *this;
}

JsonWriter& JsonWriter::end_object() {
  impl_->open.pop_back();
  return *this;
}

JsonWriter& JsonWriter::begin_array() {
  impl_->open.push_back(impl_->put(Json::array()));
  return *this;
}

JsonWriter& JsonWriter::end_array() {
  impl_->open.pop_back();
  return *this;
}

JsonWriter& JsonWriter::key(const std::string& k) {
  impl_->key = k;
  impl_->has_key = true;
  return *this;
}

JsonWriter& JsonWriter::value(double x) {
  impl_->put(std::isfinite(x) ? Json(x) : Json(nullptr));
  return *this;
}

JsonWriter& JsonWriter::value(long long x) {
  impl_->put(Json(x));
  return *this;
}

JsonWriter& JsonWriter::value(bool b) {
  impl_->put(Json(b));
  return *this;
}

JsonWriter& JsonWriter::value(const std::string& s) {
  impl_->put(Json(s));
  return *this;
}

JsonWriter& JsonWriter::null() {
  impl_->put(Json(nullptr));
  return *this;
}

JsonWriter& JsonWriter::array(const std::vector<double>& xs) {
  begin_array();
  for (const double x : xs) value(x);
  return end_array();
}

JsonWriter& JsonWriter::array(const std::vector<std::string>& xs) {
  begin_array();
  for (const auto& x : xs) value(x);
  return end_array();
}

std::string JsonWriter::str() const { return json_line(impl_->root); }

std::string json_quote(const std::string& s) { return json_line(Json(s)); }

}  // namespace nimble
