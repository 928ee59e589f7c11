#pragma once

/// The ACTUATOR_CMD commands bench_can_bridge sends, and the check of one that crossed the CAN link.

#include <cstdint>

#include <nimble/actuator_command_t.hpp>

namespace nimble::bench {

/// Command number `seq`: values on the frame layout's resolution, so they cross the link exactly.
actuator_command_t make_command(int64_t seq);

/// Whether `a` carries the values of `b`, to the frame layout's resolution (with its rolling counter).
bool same_values(const actuator_command_t& a, const actuator_command_t& b);

}  // namespace nimble::bench
