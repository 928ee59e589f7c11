#pragma once
/// Helpers of the commands' reports and plots: one number formatted printf-style, a text
/// file written whole, and a gnuplot script run in the plot directory. (ident/plots.cc has
/// its own, private to the identification plots.)

#include <filesystem>
#include <string>

namespace nimble::cli {

/// `x` formatted with the printf `format` (one double conversion; at most 63 characters).
std::string fmt(const char* format, double x);

/// Single-quoted gnuplot string ('' escapes a quote).
std::string gp_quote(const std::string& s);

/// Writes `text` to `path`. @throws std::runtime_error if it cannot be written.
void write_file(const std::filesystem::path& path, const std::string& text);

/// Writes `script` to <dir>/<name>.gp and runs gnuplot on it, its output to <dir>/<name>.log.
/// @throws std::runtime_error with the log if gnuplot fails.
void run_gnuplot(const std::filesystem::path& dir, const std::string& name, const std::string& script);

}  // namespace nimble::cli
