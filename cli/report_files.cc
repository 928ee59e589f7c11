#include "cli/report_files.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

namespace nimble::cli {

namespace fs = std::filesystem;

std::string fmt(const char* format, double x) {
  char buf[64];
  std::snprintf(buf, sizeof buf, format, x);
  return buf;
}

std::string gp_quote(const std::string& s) {
  std::string out = "'";
  for (const char c : s) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

void write_file(const fs::path& path, const std::string& text) {
  std::ofstream out(path);
  if (!out) throw std::runtime_error(path.string() + ": cannot be written");
  out << text;
  if (!out) throw std::runtime_error(path.string() + ": write failed");
}

void run_gnuplot(const fs::path& dir, const std::string& name, const std::string& script) {
  const fs::path gp = dir / (name + ".gp");
  const fs::path log = dir / (name + ".log");
  write_file(gp, script);
  const std::string cmd = "gnuplot " + gp_quote(gp.string()) + " >" + gp_quote(log.string()) + " 2>&1";
  if (std::system(cmd.c_str()) != 0) {
    std::ifstream in(log);
    std::ostringstream text;
    text << in.rdbuf();
    throw std::runtime_error("gnuplot failed on " + gp.string() + ": " + text.str());
  }
}

}  // namespace nimble::cli
