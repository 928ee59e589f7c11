#pragma once
/// PNG plots of an identification or validation, drawn by gnuplot (plots/gnuplot.h).

#include <filesystem>
#include <string>
#include <vector>

#include "ident/identify.h"
#include "ident/validate.h"

namespace nimble::ident {

/// Writes into `dir` (created if needed): derivatives.png (measured and
/// estimated state derivatives), autocorrelation.png (residual
/// autocorrelation with the 95 % bounds), psd.png (state PSDs in hover and
/// manoeuvre, cut-off marked), eigenvalues.png (complex plane).
/// Returns the paths of the PNG files.
/// @throws std::runtime_error if gnuplot is missing or fails, or a file cannot be written.
std::vector<std::string> plot_identification(const IdentResult& result, const std::string& dir);

/// Writes derivatives.png and autocorrelation.png of an open-loop validation into `dir`.
/// @throws std::runtime_error as plot_identification.
std::vector<std::string> plot_validation(const ValidationResult& result, const std::string& dir);

/// autocorrelation.png in `dir` (with its .dat and .gp): the residual autocorrelation of each fit
/// (OutputFit::whiteness) with the 95 % bounds, one panel per output, titled with its verdict.
std::string plot_autocorrelation(const std::filesystem::path& dir, const std::vector<OutputFit>& fits,
                                 const std::string& title);

}  // namespace nimble::ident
