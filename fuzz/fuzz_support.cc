#include "fuzz/fuzz_support.h"

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <stdexcept>

#include <nimble/rig_message_list.hpp>

#include "contract/decode.h"

namespace nimble::fuzz {

void finding(const std::string& what) {
  std::fprintf(stderr, "FUZZ FINDING: %s\n", what.c_str());
  std::fflush(stderr);
  std::abort();
}

namespace {

struct ScratchDir {
  std::string path;
  ScratchDir() {
    const char* tmp = std::getenv("TMPDIR");
    std::string pattern = std::string(tmp != nullptr && *tmp != '\0' ? tmp : "/tmp") + "/rig-fuzz-XXXXXX";
    if (::mkdtemp(pattern.data()) == nullptr) {
      std::perror("mkdtemp");
      std::abort();
    }
    path = pattern;
  }
  ~ScratchDir() {
    std::error_code ec;
    std::filesystem::remove_all(path, ec);
  }
};

template <typename T>
LcmType make_type() {
  LcmType t;
  t.name = T::getTypeName();
  t.decodes = [](const uint8_t* data, int size) {
    T msg{};
    return contract::decode_exact(data, size, msg);
  };
  t.check_round_trip = [](const uint8_t* data, int size) {
    T first{};
    if (!contract::decode_exact(data, size, first)) return;
    const std::string type = T::getTypeName();
    const int encoded_size = first.getEncodedSize();
    require(encoded_size == size,
            type + ": decoded " + std::to_string(size) + " bytes, re-encodes to " + std::to_string(encoded_size));
    std::vector<uint8_t> once(static_cast<std::size_t>(encoded_size));
    require(first.encode(once.data(), 0, encoded_size) == encoded_size, type + ": re-encoding failed");
    T second{};
    require(contract::decode_exact(once.data(), encoded_size, second), type + ": its own encoding does not decode");
    std::vector<uint8_t> twice(static_cast<std::size_t>(second.getEncodedSize()));
    require(second.encode(twice.data(), 0, static_cast<int>(twice.size())) == static_cast<int>(twice.size()) &&
                twice == once,
            type + ": encoding a decoded encoding changes it");
  };
  return t;
}

}  // namespace

const std::string& scratch_dir() {
  static const ScratchDir dir;
  return dir.path;
}

void write_file(const std::string& path, const uint8_t* data, std::size_t size) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  if (!out) throw std::runtime_error("cannot write " + path);
}

const std::vector<LcmType>& lcm_types() {
  static const std::vector<LcmType> types = {
#define NIMBLE_FUZZ_TYPE(T) make_type<T>(),
      NIMBLE_RIG_MESSAGES(NIMBLE_FUZZ_TYPE)
#undef NIMBLE_FUZZ_TYPE
  };
  return types;
}

const LcmType* find_lcm_type(const std::string& name) {
  for (const auto& t : lcm_types()) {
    if (t.name == name || "nimble." + t.name == name) return &t;
  }
  return nullptr;
}

std::string source_dir() { return RIG_SOURCE_DIR; }

}  // namespace nimble::fuzz
