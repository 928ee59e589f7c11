#pragma once
/// Validation of a scenario's process sections before anything is started, with the
/// same loaders the processes use, so that a bad value is reported once, up front,
/// naming its file and key.

#include "contract/rates.h"
#include "scenario/scenario.h"

namespace nimble::launcher {

/// Rates the processes of a scenario will run at.
using ProcessRates = contract::ProcessRates;

/// Loads every section, model and manoeuvre the scenario's processes will load, and checks
/// that the plant and controller agree on shared assumptions.
/// @throws ConfigError naming the file, key and value.
void validate_process_sections(const Scenario& scenario);

/// The rates of a validated scenario.
ProcessRates process_rates(const Scenario& scenario);

}  // namespace nimble::launcher
