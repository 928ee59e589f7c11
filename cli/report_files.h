#pragma once
/// Helpers of the commands' reports and plots: one number formatted printf-style (nimble::fmt,
/// core/config.h), and the identification plots' file and gnuplot helpers.

#include <filesystem>
#include <string>

#include "core/config.h"
#include "core/output_file.h"
#include "ident/plots.h"
#include "plots/gnuplot.h"

namespace nimble::cli {

/// The identification plots' gnuplot helpers (ident/plots.h); files are written with
/// nimble::write_file (core/output_file.h).
using plots::gp_quote;
using plots::run_gnuplot;

}  // namespace nimble::cli
