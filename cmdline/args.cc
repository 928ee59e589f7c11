#include "cmdline/args.h"

#include <cmath>
#include <fstream>
#include <iostream>
#include <memory>
#include <stdexcept>

#include "core/output_file.h"

namespace nimble::cmdline {

double finite_number(const std::string& text) {
  std::size_t used = 0;
  double x = NAN;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(x)) {
    throw std::invalid_argument("'" + text + "' is not a finite number");
  }
  return x;
}

std::vector<double> number_list(const std::string& text, char separator) {
  std::vector<double> out;
  std::size_t start = 0;
  while (true) {
    const std::size_t end = text.find(separator, start);
    out.push_back(finite_number(text.substr(start, end == std::string::npos ? std::string::npos : end - start)));
    if (end == std::string::npos) return out;
    start = end + 1;
  }
}

std::vector<double> number_grid(const std::string& text) {
  if (text.find(':') != std::string::npos) {
    const std::vector<double> r = number_list(text, ':');
    if (r.size() != 3 || !(r[2] > 0.0) || r[1] < r[0]) {
      throw std::invalid_argument("range must be FROM:TO:STEP with STEP > 0 and TO >= FROM: '" + text + "'");
    }
    std::vector<double> out;
    const long n = std::lround(std::floor((r[1] - r[0]) / r[2] + 1e-9));
    for (long i = 0; i <= n; ++i) out.push_back(r[0] + static_cast<double>(i) * r[2]);
    return out;
  }
  std::vector<double> out = number_list(text, ',');
  if (out.empty()) throw std::invalid_argument("empty list");
  return out;
}

const CLI::Validator kFinite(
    [](std::string& text) -> std::string {
      try {
        finite_number(text);
      } catch (const std::invalid_argument& e) {
        return e.what();
      }
      return {};
    },
    "", "FINITE");

const CLI::Validator kPowerOfTwo(
    [](std::string& text) -> std::string {
      unsigned long long m = 0;
      if (!CLI::detail::lexical_cast(text, m) || m < 8 || m > (1ULL << 40) || (m & (m - 1)) != 0) {
        return "'" + text + "' is not a power of two >= 8";
      }
      return {};
    },
    "", "POWER_OF_TWO");

const CLI::Validator kWholeNumber(
    [](std::string& text) -> std::string {
      if (text.empty() || text.size() > 19 || text.find_first_not_of("0123456789") != std::string::npos) {
        return "'" + text + "' is not a whole number >= 0";
      }
      return {};
    },
    "", "WHOLE_NUMBER");

namespace {

/// Words of `text` in lines of at most `width` characters (a word longer than that stays whole).
std::string wrap(const std::string& text, std::size_t width) {
  std::string out, line, word;
  const auto flush_word = [&] {
    if (word.empty()) return;
    if (!line.empty() && line.size() + 1 + word.size() > width) {
      out += line + "\n";
      line.clear();
    }
    line += (line.empty() ? "" : " ") + word;
    word.clear();
  };
  for (const char c : text) {
    if (c == ' ' || c == '\n') {
      flush_word();
      if (c == '\n') {
        out += line + "\n";
        line.clear();
      }
    } else {
      word += c;
    }
  }
  flush_word();
  return out + line;
}

/// CLI11's help with the option descriptions wrapped to a terminal's width.
class Formatter : public CLI::Formatter {
 public:
  std::string make_option_desc(const CLI::Option* option) const override {
    return wrap(CLI::Formatter::make_option_desc(option), 100 - get_column_width());
  }
};

}  // namespace

CommandLine::CommandLine(const std::string& program, const std::string& description)
    : program_(program), app_(description, program) {
  formatter_ = std::make_shared<Formatter>();
  formatter_->label("Usage", "usage");
  formatter_->label("OPTIONS", "options");
  formatter_->label("REQUIRED", "required");
  formatter_->column_width(34);
  app_.formatter(formatter_);
  // An option given twice takes its last value, as the shell convention goes (a script may append
  // `--json F` to a command line that has one); list options (--set) say TakeAll themselves.
  app_.option_defaults()->multi_option_policy(CLI::MultiOptionPolicy::TakeLast);
}

CLI::Option* CommandLine::add_json(std::string& target, const std::string& what) {
  return app_
      .add_option("--json", target,
                  what +
                      " as JSON to FILE; '-' writes it alone to stdout (the text then "
                      "goes to stderr or is left out)")
      ->type_name("FILE|-");
}

CLI::Option* CommandLine::add_plots(std::string& dir, const std::string& files) {
  return app_
      .add_option("--plots", dir,
                  "PNG plots via gnuplot (Debian package gnuplot-nox)" + (files.empty() ? std::string() : ": " + files))
      ->type_name("DIR");
}

std::optional<int> CommandLine::parse(const std::vector<std::string>& args) {
  // CLI11 takes a vector in reverse order (it pops arguments off its back).
  std::vector<std::string> reversed(args.rbegin(), args.rend());
  try {
    app_.parse(reversed);
  } catch (const CLI::CallForHelp&) {
    const std::string help = app_.help();
    std::cout << help << (help.empty() || help.back() != '\n' ? "\n" : "");
    return 0;
  } catch (const CLI::ParseError& e) {
    return fail(e.what());
  } catch (const std::invalid_argument& e) {
    return fail(e.what());
  }
  return std::nullopt;
}

std::optional<int> CommandLine::parse(int argc, char** argv) {
  return parse(argc > 1 ? std::vector<std::string>(argv + 1, argv + argc) : std::vector<std::string>{});
}

int CommandLine::fail(const std::string& what) const {
  std::cerr << program_ << ": " << what << "\n"
            << formatter_->make_usage(&app_, program_) << "'" << program_ << " --help' describes the options.\n";
  return kExitUsage;
}

CLI::Option* each_value(CLI::Option* option, std::function<void(const std::string&)> use) {
  const std::string option_name = option->get_name();
  return option->each([use, option_name](const std::string& value) {
    try {
      use(value);
    } catch (const CLI::Error&) {
      throw;
    } catch (const std::exception& e) {  // the rig's own parsers: std::invalid_argument, ConfigError
      // CLI11 names the option; a ConfigError from an override names it too ("--set: ...").
      std::string what = e.what();
      const std::string named = option_name + ": ";
      if (what.compare(0, named.size(), named) == 0) what.erase(0, named.size());
      throw CLI::ValidationError(what);
    }
  });
}

void write_json(const std::string& target, const std::string& json) {
  if (target == "-") {
    std::cout << json << "\n";
    return;
  }
  write_file(target, json + "\n");
}

}  // namespace nimble::cmdline
