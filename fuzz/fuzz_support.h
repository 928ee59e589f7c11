#pragma once
/// What every fuzz target of fuzz/ shares: findings, scratch files, and the LCM types by name.
///
/// A target treats the errors the rig documents for bad input (ConfigError, DataError) as the
/// expected outcome and lets everything else through to libFuzzer: an unexpected exception
/// type ends the process (std::terminate), a sanitizer report or a broken property (finding())
/// aborts it, and libFuzzer reports each as a crash with the input that caused it.

#include <cstddef>
#include <cstdint>
#include <functional>
#include <string>
#include <vector>

namespace nimble::fuzz {

/// Reports a broken property of the code under test and aborts (libFuzzer keeps the input).
[[noreturn]] void finding(const std::string& what);

/// Checks `condition`; a false one is a finding described by `what`.
inline void require(bool condition, const std::string& what) {
  if (!condition) finding(what);
}

/// A scratch directory of this process (created on first use, under $TMPDIR or /tmp, removed
/// at exit), for loaders that read files.
const std::string& scratch_dir();

/// Writes `size` bytes to `path` (replacing it). @throws std::runtime_error if it cannot.
void write_file(const std::string& path, const uint8_t* data, std::size_t size);

/// The rig's LCM types (lcmtypes/), each with its decoder and a round-trip check.
struct LcmType {
  std::string name;  ///< e.g. "truth_state_t"
  /// True if the bytes decode exactly as this type (contract::decode_exact).
  std::function<bool(const uint8_t*, int)> decodes;
  /// For bytes that decode exactly: decodes, re-encodes and decodes the result again; a finding
  /// if the re-encoded size is not the input's or the second encoding differs from the first.
  std::function<void(const uint8_t*, int)> check_round_trip;
};
/// Every type of lcmtypes/, in file order (the generated list, nimble/rig_message_list.hpp).
const std::vector<LcmType>& lcm_types();
/// The type called `name`, or nullptr.
const LcmType* find_lcm_type(const std::string& name);

/// The repository's root (for rig_configs/).
std::string source_dir();

}  // namespace nimble::fuzz
