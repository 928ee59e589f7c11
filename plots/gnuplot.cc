/// Figures drawn by gnuplot (plots/gnuplot.h).

#include "plots/gnuplot.h"

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/output_file.h"

namespace nimble::plots {
namespace {

namespace fs = std::filesystem;

/// Single-quoted shell word.
std::string sh_quote(const std::string& s) {
  std::string out = "'";
  for (const char c : s) out += (c == '\'') ? std::string("'\\''") : std::string(1, c);
  return out + "'";
}

}  // namespace

std::string gp_quote(const std::string& s) {
  std::string out = "'";
  for (const char c : s) out += (c == '\'') ? std::string("''") : std::string(1, c);
  return out + "'";
}

std::string gp_number(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

std::string png_terminal(int width, int height) {
  return "set terminal pngcairo size " + std::to_string(width) + "," + std::to_string(height) +
         " font 'sans,10'\nset termoption noenhanced\n";
}

void run_gnuplot(const std::filesystem::path& dir, const std::string& name, const std::string& script) {
  const fs::path gp = dir / (name + ".gp");
  const fs::path log = dir / (name + ".log");
  write_file(gp, script);
  const std::string cmd = "gnuplot " + sh_quote(gp.string()) + " >" + sh_quote(log.string()) + " 2>&1";
  const int status = std::system(cmd.c_str());
  if (status != 0) {
    std::ifstream in(log);
    std::ostringstream text;
    text << in.rdbuf();
    throw std::runtime_error("gnuplot failed on " + gp.string() + ": " + text.str());
  }
  // gnuplot's output is kept only when it said something (a warning worth reading).
  std::error_code ec;
  if (fs::exists(log, ec) && fs::file_size(log, ec) == 0) fs::remove(log, ec);
}

bool gnuplot_available() { return std::system("command -v gnuplot >/dev/null 2>&1") == 0; }

void require_gnuplot() {
  if (!gnuplot_available()) {
    throw std::runtime_error("--plots needs gnuplot, which is not on the PATH: install the Debian package gnuplot-nox");
  }
}

std::filesystem::path plot_dir(const std::string& dir) {
  require_gnuplot();
  std::error_code ec;
  fs::create_directories(dir, ec);
  if (ec || !fs::is_directory(dir)) throw std::runtime_error(dir + ": cannot create the plot directory");
  return fs::absolute(dir);
}

std::string plot_time_histories(const std::string& dir, const std::string& name, const std::string& title,
                                const Eigen::VectorXd& t_s, const std::vector<TimePanel>& panels) {
  return plot_panels(dir, name, title, t_s, panels, PlotAxes{});
}

std::string plot_panels(const std::string& dir, const std::string& name, const std::string& title,
                        const Eigen::VectorXd& t_s, const std::vector<TimePanel>& panels, const PlotAxes& axes) {
  if (panels.empty()) throw std::invalid_argument("plot " + name + ": no panel");
  for (const auto& panel : panels) {
    if (panel.series.empty())
      throw std::invalid_argument("plot " + name + ": panel '" + panel.title + "' has no series");
    for (const auto& c : panel.series) {
      if (c.y.size() != t_s.size()) {
        throw std::invalid_argument("plot " + name + ": series '" + c.label + "' has " + std::to_string(c.y.size()) +
                                    " samples, the time vector " + std::to_string(t_s.size()));
      }
    }
  }
  const fs::path d = plot_dir(dir);
  const fs::path dat = d / (name + ".dat");
  std::ostringstream data;
  data << "# t_s";
  for (const auto& panel : panels) {
    for (const auto& c : panel.series) {
      std::string column = panel.name + ":" + c.label;
      for (char& ch : column) ch = (ch == ' ') ? '_' : ch;
      data << " " << column;
    }
  }
  data << "\n";
  for (Eigen::Index k = 0; k < t_s.size(); ++k) {
    data << gp_number(t_s[k]);
    for (const auto& panel : panels) {
      for (const auto& c : panel.series) data << " " << gp_number(c.y[k]);
    }
    data << "\n";
  }
  write_file(dat, data.str());
  const fs::path png = d / (name + ".png");
  const int n = static_cast<int>(panels.size());
  std::ostringstream s;
  s << png_terminal(1400, 300 * n) << "set output " << gp_quote(png.string()) << "\n";
  s << "set multiplot layout " << n << ",1 title " << gp_quote(title) << "\n";
  s << "set grid\nset key top right\nset xlabel " << gp_quote(axes.xlabel) << "\n";
  if (axes.log_y) s << "set logscale y\nset format y '%.0e'\n";
  if (axes.x_max > 0.0) s << "set xrange [0:" << gp_number(axes.x_max) << "]\n";
  int column = 2;
  for (const auto& panel : panels) {
    s << "set title " << gp_quote(panel.title) << " noenhanced\n";
    s << "set ylabel " << gp_quote(panel.ylabel) << " noenhanced\n";
    s << "plot ";
    for (std::size_t i = 0; i < panel.series.size(); ++i) {
      const PlotSeries& c = panel.series[i];
      s << (i == 0 ? gp_quote(dat.string()) : std::string("''")) << " using 1:" << column++ << " with lines lw 1.2"
        << (c.dashed ? " dt 2" : "") << " lc rgb " << gp_quote(c.colour) << " title " << gp_quote(c.label)
        << (i + 1 < panel.series.size() ? ", \\\n     " : "\n");
    }
  }
  s << "unset multiplot\n";
  run_gnuplot(d, name, s.str());
  return png.string();
}

}  // namespace nimble::plots
