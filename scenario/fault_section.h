#pragma once
/// The scenario's `faults:` section: faults injected into the run (contract/faults.h).
///
///   faults:
///     - {target: MOCAP_POSE, kind: delayed, start_s: 1.0, duration_s: 2.0, params: {delay_ms: 60}}
///     - {target: ESTIMATE, kind: off, start_s: 2.0}          # to the end of the run
///
/// target: IMU, MOCAP_POSE, ESTIMATE, ACTUATOR_CMD, ACTUATOR_FB, or CAN (the CAN link, with
/// actuator_link: can). kind and its params:
///   off                       -
///   stuck                     -
///   garbage                   mode: bytes (default) | nan
///   wrong                     scale (default 1), bias (default 0), field (default: every value field)
///   slow                      divisor (integer >= 2)
///   delayed                   delay_ms (> 0)
///   intermittent              probability (0 < p <= 1)
///   CAN: loss, corrupt        probability (0 < p <= 1)
///   CAN: bus_off              -
/// start_s is simulated time; duration_s (optional) > 0, absent: to the end of the run.

#include <vector>

#include <yaml-cpp/yaml.h>

#include "contract/faults.h"

namespace nimble {

/// Reads and validates the `faults` list of a resolved scenario tree (absent: none).
/// `processes` and `can_link` are the run's: a fault on a channel nobody in the run publishes
/// is an error, as is a CAN fault without the CAN link.
/// @throws ConfigError naming `file` and the key (faults[i].kind, ...).
std::vector<contract::FaultSpec> faults_from(const YAML::Node& faults, const std::string& file,
                                             const std::vector<std::string>& processes, bool can_link,
                                             double duration_s);

}  // namespace nimble
