#pragma once
/// Argument parsing shared by the `rig` sub-commands: the usage error, a walker over
/// options and positional arguments, number and integer option values, --help, and the
/// --json target (a file or '-' for stdout).

#include <cstddef>
#include <stdexcept>
#include <string>
#include <vector>

namespace nimble::cli {

/// Bad usage: the command prints "rig <command>: <what>" and its usage, and exits kExitUsage.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

/// Walks the arguments: options with a value, and positional arguments.
class Args {
 public:
  explicit Args(const std::vector<std::string>& args) : args_(args) {}
  /// Moves to the next argument; false after the last.
  bool next() { return ++i_ < args_.size(); }
  /// The current argument.
  const std::string& arg() const { return args_[i_]; }
  /// The value of the current option (the next argument, consumed).
  /// @throws UsageError "<option> needs a value" if there is none.
  const std::string& value();

 private:
  const std::vector<std::string>& args_;
  std::size_t i_ = static_cast<std::size_t>(-1);
};

/// Number in an option value; @throws UsageError naming the option.
double number(const std::string& option, const std::string& text);

/// Integer in [lo, hi] in an option value; @throws UsageError naming the option.
int integer(const std::string& option, const std::string& text, int lo, int hi);

/// True if any argument is --help or -h.
bool wants_help(const std::vector<std::string>& args);

/// Writes `json` and a newline to the file `target`, or to stdout if `target` is "-".
/// @throws std::runtime_error if the file cannot be written.
void write_json(const std::string& target, const std::string& json);

}  // namespace nimble::cli
