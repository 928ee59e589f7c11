/// The closed loop before and after a discrepancy refit (discrepancy/closed_loop_compare.h).

#include "discrepancy/closed_loop_compare.h"

#include <exception>

#include "ident/closed_loop.h"

namespace nimble::ident {

void compare_closed_loop(DiscrepancyResult& result, const std::vector<FlightData>& flights,
                         const DerivativeModel& model, const Vehicle& vehicle, const ControllerConfig& controller,
                         const std::string& gains) {
  if (flights.size() > 1) {
    result.closed_loop_note = "not flown for pooled flights: run rig discrepancy on one flight for it";
    return;
  }
  if (flights.empty() || !flights.front().has("phi_sp")) {
    result.closed_loop_note = "the data has no phi_sp";
    return;
  }
  try {
    ClosedLoopOptions options;
    options.controller = controller;
    options.gain_set = gains;
    const ClosedLoopResult before = validate_closed_loop(flights.front(), model, vehicle, options);
    const ClosedLoopResult after = validate_closed_loop(flights.front(), result.augmented_model, vehicle, options);
    for (const char* s : {"p", "v", "phi", "delta_f"}) {
      result.closed_loop.push_back(
          {s, before.fits.at(s).r2, after.fits.at(s).r2, before.fits.at(s).rmse, after.fits.at(s).rmse});
    }
    result.closed_loop_note = "gains " + gains;
  } catch (const std::exception& e) {
    result.closed_loop_note = std::string("not flown: ") + e.what();
  }
}

}  // namespace nimble::ident
