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

}  // namespace nimble::ident
