/// The smoother's model of a flight from its sensing configuration (ident/flight_sensing.h).

#include "ident/flight_sensing.h"

namespace nimble::ident {

SmoothingOptions smoothing_options(const SensingConfig& sensing) {
  SmoothingOptions o;
  o.differentiator = sensing.velocity_differentiator;
  o.prefilter = sensing.imu_prefilter;
  o.imu_rate_hz = sensing.imu.sample_rate_hz;
  const ImuClock clock = sensing.imu.clock();
  if (!clock.identity()) o.imu_rig_utime = [clock](std::int64_t stamp) { return clock.rig_utime(stamp); };
  if (sensing.imu_prefilter.enabled) {
    o.ekf = ekf_config_matched_to_sensors(sensing.ekf, sensing.imu, sensing.mocap, sensing.velocity_differentiator);
  } else {
    o.ekf = smoother_ekf_config(sensing);
  }
  return o;
}

}  // namespace nimble::ident
