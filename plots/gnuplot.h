#pragma once
/// Figures drawn by gnuplot (Debian package gnuplot-nox): each figure is a data file plus a
/// gnuplot script in its directory, then `gnuplot <script>` renders the PNG next to them. The
/// rooms that draw (identification, the loop study, the campaigns' reports, the commands) build
/// their figures from these pieces.

#include <filesystem>
#include <string>
#include <vector>

#include <Eigen/Dense>

namespace nimble::plots {

/// One curve of a time-history panel.
struct PlotSeries {
  std::string label;
  Eigen::VectorXd y;               ///< one value per time sample
  std::string colour = "#1f77b4";  ///< gnuplot rgb colour
  bool dashed = false;
};

/// One panel of a time-history plot.
struct TimePanel {
  std::string name;  ///< short name: the data columns are <name>:<label> (spaces as _)
  std::string title;
  std::string ylabel;
  std::vector<PlotSeries> series;
};

/// Single-quoted gnuplot string ('' escapes a quote).
std::string gp_quote(const std::string& s);

/// A number as a gnuplot script or data file writes it (%.9g).
std::string gp_number(double x);

/// The pngcairo terminal of a figure `width` x `height` pixels, text not enhanced.
std::string png_terminal(int width, int height);

/// `dir` created if needed (absolute). @throws std::runtime_error if gnuplot is not on the PATH
/// (require_gnuplot) or the directory cannot be made.
std::filesystem::path plot_dir(const std::string& dir);

/// Writes `script` to <dir>/<name>.gp and runs gnuplot on it, its output to <dir>/<name>.log.
/// @throws std::runtime_error with the log if gnuplot fails.
void run_gnuplot(const std::filesystem::path& dir, const std::string& name, const std::string& script);

/// True if a `gnuplot` executable is on the PATH.
bool gnuplot_available();

/// @throws std::runtime_error naming the Debian package gnuplot-nox if gnuplot is not on the PATH.
void require_gnuplot();

/// Axes of plot_panels().
struct PlotAxes {
  std::string xlabel = "time [s]";
  bool log_y = false;
  double x_max = 0.0;  ///< > 0: the x axis ends there
};

/// Panels over any x (e.g. frequency, with a logarithmic y): as plot_time_histories.
std::string plot_panels(const std::string& dir, const std::string& name, const std::string& title,
                        const Eigen::VectorXd& x, const std::vector<TimePanel>& panels, const PlotAxes& axes);

/// Time histories over `t_s`, one panel per entry stacked under `title`: writes
/// <name>.dat (t and every series, one column each), <name>.gp and <name>.png into `dir`
/// (created if needed). Returns the path of the PNG.
/// @throws std::invalid_argument if there is no panel, a panel has no series or a series
///         is not as long as t_s; std::runtime_error if gnuplot is missing or fails, or a file
///         cannot be written.
std::string plot_time_histories(const std::string& dir, const std::string& name, const std::string& title,
                                const Eigen::VectorXd& t_s, const std::vector<TimePanel>& panels);

}  // namespace nimble::plots
