#pragma once
/// The command line of a program of the rig, parsed by CLI11 (Debian libcli11-dev) with one
/// convention for every `rig` sub-command, rig process, benchmark and tool:
/// - `-h`/`--help` prints the help on stdout and exits 0; the help is made from the options
///   themselves, so it cannot drift from what the program accepts;
/// - a usage error (unknown option, missing value or argument, a value out of range) prints
///   "<program>: <what>", the usage line and a pointer to --help on stderr and exits
///   kExitUsage (2);
/// - options take `--opt value` or `--opt=value`; numbers are checked (finite, in range) before
///   the command runs;
/// - `--json FILE|-` writes the command's JSON to FILE, or alone to stdout with '-'.

#include <functional>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

namespace nimble::cmdline {

/// Exit code for bad usage or bad input (every command line of the rig).
constexpr int kExitUsage = 2;

/// One program's command line.
class CommandLine {
 public:
  /// `program`: the program as it is typed ("rig run", "nimble_plant", "bench_can"), which the
  /// help and the messages name; `description`: what it does, the first paragraph of its help.
  CommandLine(const std::string& program, const std::string& description);

  /// The CLI11 application to add options to.
  CLI::App* operator->() { return &app_; }
  CLI::App& app() { return app_; }

  /// Adds `--json FILE|-` writing to `target`.
  CLI::Option* add_json(std::string& target, const std::string& what);

  /// Adds `--plots DIR`, PNG plots drawn by gnuplot into `dir`; `files` names them.
  CLI::Option* add_plots(std::string& dir, const std::string& files);

  /// Parses `args` (those after the program's name). Returns the exit code if the program
  /// ends here (0 after --help, kExitUsage after a usage error), else std::nullopt.
  std::optional<int> parse(const std::vector<std::string>& args);
  /// The same for main()'s arguments (argv[0] is skipped).
  std::optional<int> parse(int argc, char** argv);

  /// Reports a usage error found after parsing (between options); returns kExitUsage.
  int fail(const std::string& what) const;

 private:
  std::string program_;
  CLI::App app_;
  std::shared_ptr<CLI::Formatter> formatter_;
};

/// The finite number written in `text` (all of it).
/// @throws std::invalid_argument "'<text>' is not a finite number".
double finite_number(const std::string& text);

/// The finite numbers of a list such as "1,2.5,3" (`separator` between items).
/// @throws std::invalid_argument naming the first item that is not a finite number.
std::vector<double> number_list(const std::string& text, char separator = ',');

/// A grid of values: "A,B,C" (a list) or "FROM:TO:STEP" (STEP > 0, TO >= FROM, both ends in).
/// @throws std::invalid_argument naming the text.
std::vector<double> number_grid(const std::string& text);

/// Validator: a finite number (CLI11's own number checks let "nan" and "inf" through).
extern const CLI::Validator kFinite;

/// Validator: a whole number >= 0 written in digits (CLI11's unsigned conversion takes "-1").
extern const CLI::Validator kWholeNumber;

/// Validator: a whole number >= 8 that is a power of two (a Welch segment length).
extern const CLI::Validator kPowerOfTwo;

/// Adds a use of each value that may throw (a parser of the rig's own value syntax, such as
/// parse_override): its message becomes the option's usage error.
CLI::Option* each_value(CLI::Option* option, std::function<void(const std::string&)> use);

/// Writes `json` and a newline to the file `target`, or to stdout if `target` is "-".
/// @throws std::runtime_error if the file cannot be written.
void write_json(const std::string& target, const std::string& json);

}  // namespace nimble::cmdline
