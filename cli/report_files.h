#pragma once
/// Helpers of the commands' reports and plots: one number formatted printf-style, and the
/// identification plots' file and gnuplot helpers.

#include <filesystem>
#include <string>

#include "core/output_file.h"
#include "ident/plots.h"

namespace nimble::cli {

/// `x` formatted with the printf `format` (one double conversion; at most 63 characters).
std::string fmt(const char* format, double x);

/// The identification plots' gnuplot helpers (ident/plots.h); files are written with
/// nimble::write_file (core/output_file.h).
using ident::gp_quote;
using ident::run_gnuplot;

}  // namespace nimble::cli
