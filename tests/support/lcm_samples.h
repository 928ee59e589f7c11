#pragma once
// Every message of the contract filled with distinct values in every field (fill), and a
// field-by-field comparison that names the first field that differs (require_equal): what the
// message tests of tests/functional/ build on. Both go through the generated list of fields
// (nimble/rig_message_list.hpp), so a type or field added to lcmtypes/ is filled and compared
// without a line here.

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>
#include <type_traits>
#include <vector>

#include <catch2/catch.hpp>

#include <nimble/rig_message_list.hpp>

namespace rig_test {

// Produces a different non-zero value on every call, so that a decoded field that was left
// untouched (zero), swapped with another field or truncated cannot compare equal.
class Distinct {
 public:
  double real() {
    const int64_t k = next();
    return sign(k) * (static_cast<double>(k) + 0.125 + static_cast<double>(k) * 1.0e-7);
  }
  int64_t i64() {
    const int64_t k = next();
    return sign(k) * ((k << 40) + 0xABCDEF00 + k);  // exercises the high bytes
  }
  int32_t i32() {
    const int64_t k = next();
    return static_cast<int32_t>(sign(k) * ((k << 20) + 0x1234 + k));
  }
  int16_t i16() { return static_cast<int16_t>(1000 + next()); }
  int8_t i8() { return static_cast<int8_t>(1 + next() % 100); }
  std::string str() { return "s" + std::to_string(next()) + "-\xc3\xa4\xc3\xb6 x"; }  // UTF-8

 private:
  static int64_t sign(int64_t k) { return (k % 2 != 0) ? -1 : 1; }
  int64_t next() { return ++n_; }
  int64_t n_ = 0;
};

namespace detail {

// The field called `name` of message type M as its .lcm file declares it.
template <typename M>
const nimble::MessageFieldInfo& field_info(const char* name) {
  const nimble::MessageFieldInfo* fields = nimble::MessageFields<M>::fields();
  for (int i = 0; i < nimble::MessageFields<M>::field_count; ++i) {
    if (std::strcmp(fields[i].name, name) == 0) return fields[i];
  }
  FAIL("no field " << name << " in " << M::getTypeName());
  return fields[0];
}

// True if `name` holds the size of a variable-length array of M.
template <typename M>
bool is_array_size(const char* name) {
  const nimble::MessageFieldInfo* fields = nimble::MessageFields<M>::fields();
  for (int i = 0; i < nimble::MessageFields<M>::field_count; ++i) {
    if (std::strcmp(fields[i].size, name) == 0) return true;
  }
  return false;
}

// Fills one field of a message of type M: each element its own value; a boolean true (its
// default is false); a variable-length array `length` elements.
template <typename M>
struct Filler {
  Distinct& g;
  std::size_t length;

  void set(const char*, double& x) { x = g.real(); }
  void set(const char*, float& x) { x = static_cast<float>(g.real()); }
  void set(const char*, int64_t& x) { x = g.i64(); }
  void set(const char*, int32_t& x) { x = g.i32(); }
  void set(const char*, int16_t& x) { x = g.i16(); }
  void set(const char* name, int8_t& x) {
    x = std::strcmp(field_info<M>(name).type, "boolean") == 0 ? int8_t{1} : g.i8();
  }
  void set(const char*, uint8_t& x) { x = static_cast<uint8_t>(g.i8()); }
  void set(const char*, std::string& x) { x = g.str(); }
  template <typename T, std::size_t N>
  void set(const char* name, T (&a)[N]) {
    for (auto& x : a) set(name, x);
  }
  template <typename T>
  void set(const char* name, std::vector<T>& v) {
    v.resize(length);
    for (auto& x : v) set(name, x);
  }
  template <typename T>
  void operator()(const char* name, T& field) {
    set(name, field);
  }
};

// Sets the size fields of a message's variable-length arrays to `length`.
template <typename M>
struct SizeSetter {
  std::size_t length;
  template <typename T>
  void operator()(const char* name, T& field) {
    if constexpr (std::is_integral_v<T>) {
      if (is_array_size<M>(name)) field = static_cast<T>(length);
    }
  }
};

// Compares one field of two messages, naming it (and the element) on a difference.
struct Comparer {
  template <typename T>
  void operator()(const char* name, const T& a, const T& b) const {
    INFO(name);
    REQUIRE(a == b);
  }
  template <typename T, std::size_t N>
  void operator()(const char* name, const T (&a)[N], const T (&b)[N]) const {
    for (std::size_t i = 0; i < N; ++i)
      (*this)((std::string(name) + "[" + std::to_string(i) + "]").c_str(), a[i], b[i]);
  }
  template <typename T>
  void operator()(const char* name, const std::vector<T>& a, const std::vector<T>& b) const {
    INFO(name << ": " << a.size() << " and " << b.size() << " elements");
    REQUIRE(a.size() == b.size());
    for (std::size_t i = 0; i < a.size(); ++i) {
      (*this)((std::string(name) + "[" + std::to_string(i) + "]").c_str(), a[i], b[i]);
    }
  }
};

}  // namespace detail

// Fills every field of `m` with its own value, each variable-length array with `length`
// elements (and its size field with `length`).
template <typename M>
void fill(M& m, Distinct& g, std::size_t length = 3) {
  nimble::for_each_field(m, detail::Filler<M>{g, length});
  nimble::for_each_field(m, detail::SizeSetter<M>{length});
}

// Requires every field of `a` to equal that of `b`, naming the first that differs.
template <typename M>
void require_equal(const M& a, const M& b) {
  nimble::bind_fields(a, b, detail::Comparer{});
}

}  // namespace rig_test
