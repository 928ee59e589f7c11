// Fuzz target: the LCM log reader (ident/lcm_log.h, LcmLogReader), strict and salvaging, and the
// rig-log reader built on it (ident/rig_log.h, read_rig_log) that `rig identify`, `rig validate`
// and `rig export` use. The input is written to a file. Damage is a DataError naming the offset;
// anything else is a finding. Salvaging must read exactly the events a strict read gets before
// its error, and every event's data must lie inside the file.

#include <cstddef>
#include <cstdint>
#include <string>

#include "fuzz/fuzz_support.h"
#include "ident/flight_data.h"
#include "lcmlog/lcm_log.h"
#include "ident/rig_log.h"

using nimble::fuzz::require;
using nimble::ident::DataError;

namespace {

/// Reads every event; returns how many, and whether the read ended in a DataError.
int64_t read_all(const std::string& file, bool salvage, std::size_t file_size, bool* error) {
  *error = false;
  int64_t n = 0;
  try {
    nimble::lcmlog::LcmLogReader reader(file, salvage);
    nimble::lcmlog::LogEventRecord ev;
    while (reader.next(&ev)) {
      ++n;
      require(ev.offset >= 0 && static_cast<std::size_t>(ev.offset) + ev.data.size() + ev.channel.size() <= file_size,
              "an event larger than the file was read");
    }
    require(reader.events() == n, "LcmLogReader::events() differs from the events read");
  } catch (const DataError&) {
    *error = true;
  }
  return n;
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, std::size_t size) {
  static const std::string file = nimble::fuzz::scratch_dir() + "/fuzz.lcmlog";
  nimble::fuzz::write_file(file, data, size);

  bool strict_error = false, salvage_error = false;
  const int64_t strict = read_all(file, false, size, &strict_error);
  const int64_t salvaged = read_all(file, true, size, &salvage_error);
  if (!strict_error) {
    require(!salvage_error && salvaged == strict, "a whole log reads differently when salvaging");
  } else if (!salvage_error) {
    require(salvaged == strict, "salvaging read " + std::to_string(salvaged) + " events, the strict read " +
                                    std::to_string(strict) + " before its error");
  }

  try {
    (void)nimble::ident::read_rig_log(file);
  } catch (const DataError&) {
    // the documented outcome of a damaged log or one without the rig's channels
  }
  try {
    nimble::ident::LogReadOptions options;
    options.salvage = true;
    (void)nimble::ident::read_rig_log(file, nimble::ident::StateSource::kAuto, options);
  } catch (const DataError&) {
  }
  return 0;
}
