#pragma once
/// The rig's messages against the vehicle's physical bounds (core/data_bounds.h): which field of
/// which message type is which bounded quantity, and the check of one message through
/// BoundsTally, the one check every reader of a log applies. A message with any bounded field
/// beyond its bound (or not finite) is garbage that decoded: its readers leave it out and name it.
///
/// The bounded fields: TRUTH and ESTIMATE's body rates (p, q, r), body velocity (u, v, w), roll
/// and pitch (phi, theta), heading (psi: finite only); TRUTH's specific force (ax, ay, az) and
/// actual inputs (delta_f, delta_t, delta_d, delta_w); ACTUATOR_FB's inputs; ACTUATOR_CMD's
/// delta_f (delta_f_cmd, in delta_f mode); ATTITUDE_SP's roll set-point (phi_sp); IMU's gyro
/// (p, q, r) and accelerometer (ax, ay, az). Other fields (positions, quaternions, counters) have
/// no bound in the vehicle file.

#include <cstdint>
#include <string>

#include "core/data_bounds.h"

namespace nimble::contract {

/// What check_message_bounds() found.
enum class BoundsResult {
  kWithin,       ///< every bounded field finite and within its bound (or a type without any)
  kBeyond,       ///< some field beyond: counted in the tally
  kUndecodable,  ///< not exactly one message of the channel's type (nothing counted)
  kUnknown,      ///< a channel the contract does not know (nothing counted)
};

/// True if messages of type `type` ("truth_state_t") have bounded fields.
bool type_has_bounds(const std::string& type);

/// Decodes `size` bytes of a message on `channel` as its contract type and checks its bounded
/// fields at rig time `t_s` [s] through `tally`, each named by `channel` and field
/// ("omega_body_radps[0]"); `event` is its log event number (-1: none). A message of a type
/// without bounded fields is not decoded (kWithin).
BoundsResult check_message_bounds(const std::string& channel, const void* data, int size, double t_s,
                                  BoundsTally& tally, std::int64_t event = -1);

/// The same for a message already decoded as its type M (a rig message type): true if within.
template <class M>
bool message_within_bounds(const std::string& channel, const M& m, double t_s, BoundsTally& tally,
                           std::int64_t event = -1);

}  // namespace nimble::contract
