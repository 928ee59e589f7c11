#pragma once
/// What the discrepancy report's text (discrepancy_report.cc) and its files
/// (discrepancy_report_files.cc) share; internal to discrepancy/.

#include <string>

#include "discrepancy/discrepancy.h"

namespace nimble::ident {

/// A trial's candidate as the reports name it: a term with its equation and expression (the
/// expression between `quote`s).
std::string trial_name(const CandidateTrial& t, const std::string& quote);

/// A number as the reports print it (`format`, printf-style, e.g. "%.4g").
std::string report_number(double x, const char* format = "%.4g");

/// Refuses a gap that is not finite (discrepancy_report.cc): a record without excitation that
/// reached the workflow is an error in the reports, never a printed "nan" or a JSON null.
/// @throws std::logic_error naming the number.
void require_finite_gap(const DiscrepancyResult& r);

}  // namespace nimble::ident
