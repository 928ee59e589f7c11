#include "core/vehicle.h"

#include <cmath>
#include <sstream>

namespace nimble {

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
    why << "Ixx*Izz - Ixz^2 = " << v.Ic()
        << " must be > 0 (Ixx=" << v.Ixx_kgm2 << ", Izz=" << v.Izz_kgm2
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
