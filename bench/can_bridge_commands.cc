#include "bench/can_bridge_commands.h"

#include <cmath>

namespace nimble::bench {

actuator_command_t make_command(int64_t seq) {
  actuator_command_t c{};
  c.utime = seq;  // overwritten with the publish time when sent; not carried by the frames
  c.seq = seq;
  c.mode = actuator_command_t::MODE_DELTA_F;
  const int k = static_cast<int>(seq % 200) - 100;  // delta_f = 0.02 k rad/s
  c.flap_freq_collective_radps = 106.80;
  c.delta_f_radps = 0.02 * k;
  c.flap_freq_left_radps = 106.80 + 0.01 * k;
  c.flap_freq_right_radps = 106.80 - 0.01 * k;
  c.throttle_pct = 55.0 + 0.01 * static_cast<double>(seq % 100);
  c.dihedral_rad = 0.0001 * static_cast<double>(seq % 1000 - 500);
  c.wing_root_rad = -0.0001 * static_cast<double>(seq % 700 - 350);
  c.input_utime = -1;
  c.rolling_counter = static_cast<int8_t>(seq % 16);
  c.source = "bench_can_bridge";
  return c;
}

bool same_values(const actuator_command_t& a, const actuator_command_t& b) {
  auto near = [](double x, double y, double tol) { return std::fabs(x - y) <= tol; };
  return a.mode == b.mode && near(a.flap_freq_left_radps, b.flap_freq_left_radps, 1e-6) &&
         near(a.flap_freq_right_radps, b.flap_freq_right_radps, 1e-6) && near(a.delta_f_radps, b.delta_f_radps, 1e-6) &&
         near(a.flap_freq_collective_radps, b.flap_freq_collective_radps, 1e-6) &&
         near(a.throttle_pct, b.throttle_pct, 1e-6) && near(a.dihedral_rad, b.dihedral_rad, 1e-7) &&
         near(a.wing_root_rad, b.wing_root_rad, 1e-7) && a.rolling_counter == b.rolling_counter;
}

}  // namespace nimble::bench
