#include "core/config_fields.h"

namespace nimble {

Eigen::Vector3d get_vec3_or(ConfigMap& map, const std::string& key, const Eigen::Vector3d& fallback, const Range& range,
                            const AxisNames& names) {
  if (!map.has(key)) return fallback;
  ConfigMap sub = map.get_map(key);
  Eigen::Vector3d v;
  for (int i = 0; i < 3; ++i) v[i] = sub.get_double_or(names[static_cast<std::size_t>(i)], fallback[i], range);
  sub.finish();
  return v;
}

long long get_int_or(ConfigMap& map, const std::string& key, long long fallback, const Range& range) {
  if (!map.has(key)) return fallback;
  return map.get_int(key, range);
}

bool get_bool_or(ConfigMap& map, const std::string& key, bool fallback) {
  if (!map.has(key)) return fallback;
  return map.get_bool(key);
}

}  // namespace nimble
