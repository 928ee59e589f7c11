#include "contract/message_bounds.h"

#include <initializer_list>

#include <nimble/rig_message_list.hpp>

#include "contract/channels.h"
#include "contract/decode.h"

namespace nimble::contract {
namespace {

/// One message's check: each bounded field through BoundsTally, named only when it does not fit.
struct Check {
  const std::string& channel;
  double t_s;
  BoundsTally& tally;
  std::int64_t event;
  bool ok = true;

  void operator()(const char* field, double value, const char* quantity) {
    if (tally.fits(quantity, t_s, value)) return;
    tally.count(channel, field, quantity, t_s, value, event);
    ok = false;
  }
  template <std::size_t N>
  void operator()(const char* field, const double (&values)[N], const char* const (&quantities)[N]) {
    for (std::size_t i = 0; i < N; ++i) {
      if (quantities[i] == nullptr || tally.fits(quantities[i], t_s, values[i])) continue;
      tally.count(channel, std::string(field) + "[" + std::to_string(i) + "]", quantities[i], t_s, values[i], event);
      ok = false;
    }
  }
};

constexpr const char* kRates[3] = {"p", "q", "r"};
constexpr const char* kVelocity[3] = {"u", "v", "w"};
constexpr const char* kEuler[3] = {"phi", "theta", "psi"};
constexpr const char* kForce[3] = {"ax", "ay", "az"};

void fields(Check& c, const truth_state_t& m) {
  c("velocity_body_mps", m.velocity_body_mps, kVelocity);
  c("euler_rad", m.euler_rad, kEuler);
  c("omega_body_radps", m.omega_body_radps, kRates);
  c("specific_force_body_mps2", m.specific_force_body_mps2, kForce);
  c("delta_f_radps", m.delta_f_radps, "delta_f");
  c("throttle_pct", m.throttle_pct, "delta_t");
  c("dihedral_rad", m.dihedral_rad, "delta_d");
  c("wing_root_rad", m.wing_root_rad, "delta_w");
}

void fields(Check& c, const estimator_state_t& m) {
  c("euler_rad", m.euler_rad, kEuler);
  c("velocity_body_mps", m.velocity_body_mps, kVelocity);
  c("omega_body_radps", m.omega_body_radps, kRates);
}

void fields(Check& c, const actuator_feedback_t& m) {
  c("delta_f_radps", m.delta_f_radps, "delta_f");
  c("dihedral_rad", m.dihedral_rad, "delta_d");
  c("wing_root_rad", m.wing_root_rad, "delta_w");
  c("throttle_pct", m.throttle_pct, "delta_t");
}

void fields(Check& c, const actuator_command_t& m) {
  if (m.mode == actuator_command_t::MODE_DELTA_F) c("delta_f_radps", m.delta_f_radps, "delta_f_cmd");
}

void fields(Check& c, const attitude_setpoint_t& m) { c("roll_sp_rad", m.roll_sp_rad, "phi_sp"); }

void fields(Check& c, const imu_sample_t& m) {
  c("gyro_radps", m.gyro_radps, kRates);
  c("accel_mps2", m.accel_mps2, kForce);
}

/// A type without bounded fields.
template <class M>
void fields(Check&, const M&) {}

}  // namespace

template <class M>
bool message_within_bounds(const std::string& channel, const M& m, double t_s, BoundsTally& tally, std::int64_t event) {
  Check c{channel, t_s, tally, event};
  fields(c, m);
  if (!c.ok) tally.count_message();
  return c.ok;
}
#define NIMBLE_MESSAGE_WITHIN_BOUNDS_OF(T) \
  template bool message_within_bounds<T>(const std::string&, const T&, double, BoundsTally&, std::int64_t);
NIMBLE_RIG_MESSAGES(NIMBLE_MESSAGE_WITHIN_BOUNDS_OF)
#undef NIMBLE_MESSAGE_WITHIN_BOUNDS_OF

bool type_has_bounds(const std::string& type) {
  for (const char* t : {"truth_state_t", "estimator_state_t", "actuator_feedback_t", "actuator_command_t",
                        "attitude_setpoint_t", "imu_sample_t"}) {
    if (type == t) return true;
  }
  return false;
}

BoundsResult check_message_bounds(const std::string& channel, const void* data, int size, double t_s,
                                  BoundsTally& tally, std::int64_t event) {
  const ChannelSpec* spec = find_channel(channel);
  if (spec == nullptr) return BoundsResult::kUnknown;
  if (!type_has_bounds(spec->type)) return BoundsResult::kWithin;
  BoundsResult result = BoundsResult::kUnknown;
  with_message_type(spec->type, [&](auto type) {
    typename decltype(type)::type m{};
    if (!decode_exact(data, size, m)) {
      result = BoundsResult::kUndecodable;
    } else {
      result = message_within_bounds(channel, m, t_s, tally, event) ? BoundsResult::kWithin : BoundsResult::kBeyond;
    }
  });
  return result;
}

}  // namespace nimble::contract
