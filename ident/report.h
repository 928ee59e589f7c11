#pragma once
/// Text and JSON reports of an identification and of an open-loop validation
/// (the output of rig identify and rig validate).

#include <string>
#include <vector>

#include "ident/identify.h"
#include "ident/validate.h"

namespace nimble::ident {

/// Human-readable report: data and processing, parameter table (value,
/// sigma, 100 sigma/|value|, for white and coloured residuals), flagged
/// correlations, accuracy metrics, whiteness, eigenvalues and modes with
/// non-dimensional eigenvectors, state PSDs of hover and manoeuvre.
std::string identification_text(const IdentResult& result);

/// One JSON object with at least "parameters" {name: {value, sigma, ...}},
/// "metrics" {output: {rxy, r2, rmse, rmse_pct_range}}, "eigenvalues"
/// ([re, im] pairs) and "whiteness" {output: fraction_outside}; `model_out`
/// and `plots` are recorded when not empty.
std::string identification_json(const IdentResult& result, const std::string& model_out,
                                const std::vector<std::string>& plots);

/// The same record identified by OLS and by WLS, side by side as thesis Appendix D prints them
/// (Tables D.1, D.2): per parameter the estimate, |sigma| and 100 |sigma / estimate| of each, with
/// sigma by the thesis's white-residual formula.
/// @throws std::invalid_argument if the two are not OLS and WLS of the same parameters.
std::string methods_comparison_text(const IdentResult& ols, const IdentResult& wls);
/// The same as a JSON value: [{name, ols: {value, sigma, rel_sigma_pct}, wls: {...}}].
std::string methods_comparison_json(const IdentResult& ols, const IdentResult& wls);

/// Human-readable report of an open-loop validation: metrics and whiteness per state derivative.
std::string validation_text(const ValidationResult& result);

/// One JSON object with "metrics" {output: {rxy, r2, rmse, rmse_pct_range}},
/// "whiteness" {output: fraction_outside} and details.
std::string validation_json(const ValidationResult& result, const std::vector<std::string>& plots);

}  // namespace nimble::ident
