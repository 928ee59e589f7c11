#pragma once
/// Open-loop validation of a linear model on flight data (thesis Section 9.2,
/// Tables 7-8): the state derivatives predicted by x_dot = A x + B u from the
/// measured (processed) states and inputs, against the differentiated
/// measured states.
///
/// Closed-loop validation (thesis Tables 9-11) needs the attitude controller;
/// it is in ident/closed_loop.h (library nimble_ident_closed_loop).

#include <cstddef>
#include <string>
#include <vector>

#include "core/model.h"
#include "core/vehicle.h"
#include "ident/identify.h"

namespace nimble::ident {

/// Options of validate_open_loop().
struct ValidationOptions {
  ProcessingOptions processing;
  std::size_t whiteness_lags = 50;
  std::size_t whiteness_lag_step = 0;  ///< samples per lag; 0: round(rate / (2 cutoff))
};

/// Result of an open-loop validation.
struct ValidationResult {
  std::string source;
  DerivativeModel model;
  Vehicle vehicle;
  StateSpace state_space;
  UniformData data;                ///< processed data with "<state>_dot"
  std::vector<OutputFit> fits;     ///< one per state derivative: "p_dot", "v_dot", "phi_dot", ...
  std::vector<std::string> notes;  ///< diagnostics skipped on a record too short for them (whiteness)
};

/// Predicts every state derivative of `model` from the measured states and
/// inputs and reports the metrics (P = 1 in R2: no parameter is fitted to
/// this data) and the residual whiteness of each.
/// @throws DataError if the data lacks a state or input of the model;
///         std::invalid_argument for invalid processing options.
ValidationResult validate_open_loop(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                    const ValidationOptions& options);

}  // namespace nimble::ident
