#include "cli/args.h"

#include <cmath>
#include <fstream>
#include <iostream>

namespace nimble::cli {

const std::string& Args::value() {
  if (i_ + 1 >= args_.size()) throw UsageError(args_[i_] + " needs a value");
  return args_[++i_];
}

double number(const std::string& option, const std::string& text) {
  std::size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(x)) {
    throw UsageError(option + ": '" + text + "' is not a finite number");
  }
  return x;
}

int integer(const std::string& option, const std::string& text, int lo, int hi) {
  const double x = number(option, text);
  if (x != static_cast<double>(static_cast<long long>(x)) || x < lo || x > hi) {
    throw UsageError(option + ": '" + text + "' must be an integer in [" + std::to_string(lo) + ", " +
                     std::to_string(hi) + "]");
  }
  return static_cast<int>(x);
}

bool wants_help(const std::vector<std::string>& args) {
  for (const auto& a : args) {
    if (a == "--help" || a == "-h") return true;
  }
  return false;
}

void write_json(const std::string& target, const std::string& json) {
  if (target == "-") {
    std::cout << json << "\n";
    return;
  }
  std::ofstream out(target);
  if (!out) throw std::runtime_error(target + ": cannot be written");
  out << json << "\n";
  if (!out) throw std::runtime_error(target + ": write failed");
}

}  // namespace nimble::cli
