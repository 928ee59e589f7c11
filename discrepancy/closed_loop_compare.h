#pragma once
/// The closed loop before and after `rig discrepancy`'s refit: the model and the augmented one
/// each flown by the attitude controller's copy (ident/closed_loop.h) on the flight's phi_sp.

#include <string>
#include <vector>

#include "controller/attitude_controller.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "discrepancy/discrepancy.h"
#include "ident/flight_data.h"

namespace nimble::ident {

/// The closed loop before and after a discrepancy refit (result.closed_loop, closed_loop_note), as
/// `rig discrepancy` reports it: `model` and result.augmented_model each flown by the controller
/// copy `controller` with `gains` on the one flight's phi_sp. Pooled flights, a flight without
/// phi_sp or a failing simulation are not flown, and closed_loop_note says why.
void compare_closed_loop(DiscrepancyResult& result, const std::vector<FlightData>& flights,
                         const DerivativeModel& model, const Vehicle& vehicle, const ControllerConfig& controller,
                         const std::string& gains);

}  // namespace nimble::ident
