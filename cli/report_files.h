#pragma once
/// Helpers of the commands' reports and plots: one number formatted printf-style, and the
/// identification plots' file and gnuplot helpers.

#include <filesystem>
#include <string>

#include "ident/plots.h"

namespace nimble::cli {

/// `x` formatted with the printf `format` (one double conversion; at most 63 characters).
std::string fmt(const char* format, double x);

/// The identification plots' gnuplot helpers (ident/plots.h): gp_quote, write_text (as
/// write_file) and run_gnuplot.
using ident::gp_quote;
using ident::run_gnuplot;
inline void write_file(const std::filesystem::path& path, const std::string& text) { ident::write_text(path, text); }

}  // namespace nimble::cli
