#pragma once
/// The discrepancy workflow's parts that check the sensors before the search and report it
/// (discrepancy/data_compatibility.h: discrepancy_compat.cc, discrepancy_compat_report.cc), and the
/// report of the forms tested as given; the rest of the workflow's parts: discrepancy_parts.h.

#include <cstddef>
#include <ostream>
#include <string>
#include <vector>

#include "discrepancy/discrepancy_parts.h"

namespace nimble::ident::discrepancy_parts {

// --- discrepancy_compat.cc ---

/// The data-compatibility stage of one flight (discrepancy/data_compatibility.h): checks the record,
/// names its significant sensor errors whose signatures hold in res.effects (with channel and
/// interval), keeps the stage's result in res.compatibility (with the baseline's held-out gap on
/// the record as recorded when a correction was made) and returns the corrected record.
FlightData compatibility_stage(const FlightData& recorded, const DerivativeModel& model, const Vehicle& vehicle,
                               const std::vector<std::string>& inputs, const DiscrepancyOptions& options,
                               DiscrepancyResult& res);

/// The stage's significant errors without their signature located as structure (unexplained);
/// actuator_delay ambiguous with a time offset where a flight's kinematics were not checked.
/// Returns the stage's alarm tests (three per checked flight).
std::size_t sensor_findings(DiscrepancyResult& res);

// --- discrepancy_compat_report.cc ---

/// The stage in the text report, and a named sensor error's line under "named effects".
void print_compatibility(std::ostream& o, const DiscrepancyResult& r);
void print_sensor_effect(std::ostream& o, const NamedEffect& e);
/// The stage's section of report.md ("" when it did not run).
std::string compatibility_markdown(const DiscrepancyResult& r);

/// The term tests' lines in the text (DiscrepancyOptions::test_terms; their JSON: discrepancy_json.cc).
void print_term_tests(std::ostream& o, const DiscrepancyResult& r);

}  // namespace nimble::ident::discrepancy_parts
