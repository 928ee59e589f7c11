#include "core/vehicle.h"

#include <cmath>
#include <sstream>

#include "core/param_table.h"

namespace nimble {

const ParamTable<DataBounds>& data_bounds_params() {
  using C = DataBounds;
  static const ParamTable<C> table = {
      {"rate_max_radps", &C::rate_max_radps, Range::positive(), "rad/s",
       "bound of |p|, |q|, |r|; assumption: above the MPU-6000 gyro's largest range (34.9 rad/s), about 8x the "
       "thesis's largest |p| (Table 9.4)"},
      {"speed_max_mps", &C::speed_max_mps, Range::positive(), "m/s",
       "bound of |u|, |v|, |w|; assumption: about 12x the thesis's fastest flight (v 1.60 m/s, paper Section VI)"},
      {"angle_max_rad", &C::angle_max_rad, Range::positive(), "rad",
       "bound of |phi|, |theta|, |phi_sp|: pi, an Euler angle of an attitude lies within +-pi"},
      {"delta_f_max_radps", &C::delta_f_max_radps, Range::positive(), "rad/s",
       "bound of |delta_f|, |delta_f_cmd|; assumption: 2x the rig's per-wing ceiling (251 rad/s), about 4x the "
       "thesis's delta_f range (Table 9)"},
      {"throttle_max_pct", &C::throttle_max_pct, Range::positive(), "%",
       "bound of |delta_t|: a throttle is 0-100 % of full scale"},
      {"servo_max_rad", &C::servo_max_rad, Range::positive(), "rad",
       "bound of |delta_d|, |delta_w|; assumption: +-90 deg, a hobby servo's full travel"},
      {"specific_force_max_mps2", &C::specific_force_max_mps2, Range::positive(), "m/s^2",
       "bound of |ax|, |ay|, |az|; assumption: above the MPU-6000 accelerometer's largest range (16 g, 156.9 m/s^2)"},
  };
  return table;
}

double Vehicle::flap_frequency_radps() const { return 2.0 * M_PI * flap_frequency_hz; }

Vehicle vehicle_from_config(ConfigMap& map) {
  Vehicle v;
  v.file = map.file();
  v.name = map.get_string("name");
  v.mass_kg = map.get_double("mass_kg", Range::positive());

  ConfigMap inertia = map.get_map("inertia_kgm2");
  v.Ixx_kgm2 = inertia.get_double("Ixx", Range::positive());
  v.Iyy_kgm2 = inertia.get_double("Iyy", Range::positive());
  v.Izz_kgm2 = inertia.get_double("Izz", Range::positive());
  v.Ixz_kgm2 = inertia.get_double("Ixz");
  inertia.finish();
  if (!(v.Ic() > 0.0)) {
    std::ostringstream why;
    why << "Ixx*Izz - Ixz^2 = " << v.Ic() << " must be > 0 (Ixx=" << v.Ixx_kgm2 << ", Izz=" << v.Izz_kgm2
        << "): not a physical inertia tensor";
    inertia.fail("Ixz", why.str());
  }

  ConfigMap wing = map.get_map("wing");
  v.wing_span_m = wing.get_double("span_m", Range::positive());
  v.wing_area_m2 = wing.get_double("area_m2", Range::positive());
  v.mean_chord_m = wing.get_double("mean_chord_m", Range::positive());
  v.r2_m = wing.get_double("r2_m", Range::positive());
  wing.finish();

  ConfigMap flapping = map.get_map("flapping");
  v.flap_frequency_hz = flapping.get_double("mean_frequency_hz", Range::positive());
  v.flap_amplitude_rad = flapping.get_double("amplitude_rad", Range{0.0, M_PI, true, false});
  flapping.finish();

  if (map.has("data_bounds")) {
    ConfigMap bounds = map.get_map("data_bounds");
    read_params(bounds, data_bounds_params(), v.data_bounds);
    bounds.finish();
  }

  v.air_density_kgpm3 = map.get_double("air_density_kgpm3", Range::positive());
  v.gravity_mps2 = map.get_double("gravity_mps2", Range::positive());
  map.finish();
  return v;
}

Vehicle load_vehicle(const std::string& file) {
  ConfigMap map = ConfigMap::load_file(file);
  return vehicle_from_config(map);
}

}  // namespace nimble
