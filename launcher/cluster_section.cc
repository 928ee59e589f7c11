#include "launcher/cluster_section.h"

#include <regex>

namespace nimble::launcher {
namespace {

/// Slurm's --time formats: minutes, minutes:seconds, hours:minutes:seconds, days-hours,
/// days-hours:minutes, days-hours:minutes:seconds.
bool valid_time_limit(const std::string& t) {
  static const std::regex re(
      R"(^(\d+|\d+:\d+|\d+:\d+:\d+|\d+-\d+|\d+-\d+:\d+|\d+-\d+:\d+:\d+|UNLIMITED|unlimited|infinite)$)");
  return std::regex_match(t, re);
}

}  // namespace

ClusterSettings cluster_settings_from(const Scenario& s) {
  ClusterSettings c;
  if (!s.has_section("cluster")) return c;
  {
    ConfigMap m = s.section("cluster");
    c.partition = m.get_string_or("partition", c.partition);
    c.account = m.get_string_or("account", c.account);
    c.time_limit = m.get_string_or("time_limit", c.time_limit);
    if (!valid_time_limit(c.time_limit)) {
      m.fail("time_limit", "must be a Slurm time limit: MM, MM:SS, HH:MM:SS, D-HH, D-HH:MM or D-HH:MM:SS");
    }
    if (m.has("cpus_per_task")) c.cpus_per_task = static_cast<int>(m.get_int("cpus_per_task", Range::closed(1, 1024)));
    if (m.has("memory_mb_per_cpu")) {
      c.memory_mb_per_cpu = static_cast<int>(m.get_int("memory_mb_per_cpu", Range::closed(0, 1 << 24)));
    }
    if (m.has("chunk_size")) c.chunk_size = static_cast<std::size_t>(m.get_int("chunk_size", Range::closed(1, 1e9)));
    c.rig = m.get_string_or("rig", c.rig);
    m.finish();
  }
  return c;
}

}  // namespace nimble::launcher
