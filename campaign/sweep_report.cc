#include "campaign/sweep_report.h"

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <sstream>
#include <stdexcept>

#include "core/output_file.h"
#include "core/json_line.h"

namespace nimble::campaign {

// One run is the launcher's (run plan, executors, report); a campaign flies many.
using namespace launcher;
namespace {

namespace fs = std::filesystem;

constexpr double kDegPerRad = 180.0 / M_PI;

/// The three quantities of a trace: name in the files, unit, scale from the trace's unit.
struct Quantity {
  const char* name;
  const char* unit;
  const char* title;
};
constexpr Quantity kQuantities[] = {
    {"p", "rad/s", "roll rate p [rad/s]"},
    {"v", "m/s", "lateral velocity v [m/s]"},
    {"phi", "deg", "roll phi [deg]"},
};

const Envelope& envelope_of(const SetReport& s, std::size_t q) { return q == 0 ? s.p : q == 1 ? s.v : s.phi_deg; }

/// Shortest of %.15g, %.16g and %.17g that reads back to the same double (so 0.1 is "0.1", not
/// "0.10000000000000001"); empty for NaN or infinity.
std::string number(double x) {
  if (!std::isfinite(x)) return "";
  char buf[40];
  for (const int digits : {15, 16}) {
    std::snprintf(buf, sizeof buf, "%.*g", digits, x);
    if (std::strtod(buf, nullptr) == x) return buf;
  }
  std::snprintf(buf, sizeof buf, "%.17g", x);
  return buf;
}

/// Fixed-point text with `decimals` digits, never "-0".
std::string fixed(double x, int decimals) {
  std::string s(static_cast<std::size_t>(std::snprintf(nullptr, 0, "%.*f", decimals, x)), '\0');
  std::snprintf(s.data(), s.size() + 1, "%.*f", decimals, x);
  if (s[0] == '-' && s.find_first_not_of("-0.") == std::string::npos) s.erase(0, 1);
  return s;
}

/// Text for XML and HTML: the five special characters as entities, control characters XML does
/// not allow as '?'.
std::string escape_xml(const std::string& s) {
  std::string out;
  out.reserve(s.size());
  for (const char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      case '\'': out += "&#39;"; break;
      default:
        if (static_cast<unsigned char>(c) < 0x20 && c != '\t' && c != '\n' && c != '\r') {
          out += '?';
        } else {
          out += c;
        }
    }
  }
  return out;
}

/// A CSV field in double quotes, embedded quotes doubled.
std::string csv_quoted(const std::string& s) {
  std::string q = "\"";
  for (const char c : s) q += c == '"' ? std::string("\"\"") : std::string(1, c);
  return q + "\"";
}

/// "90.0 % [69.9, 97.2] %" style text of a rate and its interval.
std::string rate_text(const Proportion& r) {
  return fixed(100.0 * r.p, 1) + " % (95 % interval " + fixed(100.0 * r.lo, 1) + "-" + fixed(100.0 * r.hi, 1) + " %)";
}

/// Samples a run has: the shortest of its p, v and phi (0 without a trace).
std::size_t samples(const RunTrace& t) { return std::min({t.p.size(), t.v.size(), t.phi.size()}); }

Envelope envelope(const std::vector<const RunTrace*>& traces, std::size_t grid, double dt_s,
                  const std::vector<double> RunTrace::*member, double scale) {
  Envelope e;
  std::vector<double> at;
  for (std::size_t k = 0; k < grid; ++k) {
    at.clear();
    for (const RunTrace* t : traces) {
      if (k >= samples(*t)) continue;
      const double x = (t->*member)[k];
      if (std::isfinite(x)) at.push_back(x * scale);
    }
    e.t_s.push_back(static_cast<double>(k) * dt_s);
    e.n.push_back(static_cast<int>(at.size()));
    e.p5.push_back(percentile(at, 5.0));
    e.p50.push_back(percentile(at, 50.0));
    e.p95.push_back(percentile(at, 95.0));
  }
  return e;
}

// --- SVG --------------------------------------------------------------------------------------

constexpr double kSvgWidth = 760.0;
constexpr double kPlotLeft = 80.0, kPlotRight = 740.0;  ///< plot area x extent [px]
constexpr double kHeader = 64.0;                        ///< title block height [px]
constexpr double kPanelHeight = 240.0;                  ///< one panel with its title and ticks [px]
constexpr double kPlotTop = 30.0, kPlotBottom = 200.0;  ///< plot area within a panel [px]

/// Ticks of an axis over [lo, hi]: a step of 1, 2 or 5 times a power of ten giving about
/// `target` intervals, the range widened to whole steps.
struct Axis {
  double lo = 0.0, hi = 1.0, step = 1.0;
  int decimals = 0;
  long long first = 0, last = 0;  ///< tick k is at k * step
};

Axis nice_axis(double lo, double hi, int target) {
  // A range too narrow for its magnitude (a constant quantity): widened around its middle, so
  // that the ticks stay few and their indices small.
  if (!(hi - lo > 1e-9 * std::max(std::fabs(lo), std::fabs(hi)))) {
    const double mid = 0.5 * (lo + hi);
    const double pad = mid == 0.0 ? 1.0 : std::fabs(mid) * 0.1;
    lo = mid - pad;
    hi = mid + pad;
  }
  const double raw = (hi - lo) / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double f = raw / mag;
  Axis a;
  a.step = (f <= 1.0 ? 1.0 : f <= 2.0 ? 2.0 : f <= 5.0 ? 5.0 : 10.0) * mag;
  a.decimals = std::max(0, -static_cast<int>(std::floor(std::log10(a.step) + 1e-9)));
  a.first = static_cast<long long>(std::floor(lo / a.step + 1e-9));
  a.last = static_cast<long long>(std::ceil(hi / a.step - 1e-9));
  if (a.last <= a.first) a.last = a.first + 1;
  a.lo = static_cast<double>(a.first) * a.step;
  a.hi = static_cast<double>(a.last) * a.step;
  return a;
}

/// One panel of a set's figure: band, median, axes, ticks and title, its top at `top` [px].
void svg_panel(std::ostringstream& out, const Envelope& e, const Quantity& q, double top, const Axis& x) {
  const double y0 = top + kPlotTop, y1 = top + kPlotBottom;
  out << "<text x=\"" << fixed(kPlotLeft, 0) << "\" y=\"" << fixed(top + 18.0, 1)
      << "\" font-size=\"14\" font-weight=\"bold\">" << escape_xml(q.title) << "</text>\n";
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  for (std::size_t k = 0; k < e.t_s.size(); ++k) {
    if (e.n[k] == 0) continue;
    lo = std::min(lo, e.p5[k]);
    hi = std::max(hi, e.p95[k]);
  }
  const std::string frame = "<rect x=\"" + fixed(kPlotLeft, 1) + "\" y=\"" + fixed(y0, 1) + "\" width=\"" +
                            fixed(kPlotRight - kPlotLeft, 1) + "\" height=\"" + fixed(y1 - y0, 1) +
                            "\" fill=\"none\" stroke=\"#444\" stroke-width=\"1\"/>\n";
  if (!std::isfinite(hi - lo)) {
    out << "<text x=\"" << fixed((kPlotLeft + kPlotRight) / 2, 1) << "\" y=\"" << fixed((y0 + y1) / 2, 1)
        << "\" text-anchor=\"middle\" font-size=\"13\">"
        << (hi >= lo ? "values beyond the range of a plot" : "no finite sample") << "</text>\n"
        << frame;
    return;
  }
  const Axis y = nice_axis(lo, hi, 4);
  const auto px = [&](double t) { return kPlotLeft + (t - x.lo) / (x.hi - x.lo) * (kPlotRight - kPlotLeft); };
  const auto py = [&](double v) { return y1 - (v - y.lo) / (y.hi - y.lo) * (y1 - y0); };
  const auto point = [&](double t, double v) { return fixed(px(t), 2) + "," + fixed(py(v), 2); };

  // Grid lines and tick labels.
  for (long long k = y.first; k <= y.last; ++k) {
    const double v = static_cast<double>(k) * y.step;
    out << "<line x1=\"" << fixed(kPlotLeft - 4.0, 1) << "\" y1=\"" << fixed(py(v), 2) << "\" x2=\""
        << fixed(kPlotRight, 1) << "\" y2=\"" << fixed(py(v), 2) << "\" stroke=\"#ddd\" stroke-width=\"1\"/>\n";
    out << "<text x=\"" << fixed(kPlotLeft - 7.0, 1) << "\" y=\"" << fixed(py(v) + 4.0, 2)
        << "\" text-anchor=\"end\" font-size=\"11\">" << fixed(v, y.decimals) << "</text>\n";
  }
  for (long long k = x.first; k <= x.last; ++k) {
    const double t = static_cast<double>(k) * x.step;
    out << "<line x1=\"" << fixed(px(t), 2) << "\" y1=\"" << fixed(y0, 1) << "\" x2=\"" << fixed(px(t), 2) << "\" y2=\""
        << fixed(y1 + 4.0, 1) << "\" stroke=\"#ddd\" stroke-width=\"1\"/>\n";
    out << "<text x=\"" << fixed(px(t), 2) << "\" y=\"" << fixed(y1 + 16.0, 1)
        << "\" text-anchor=\"middle\" font-size=\"11\">" << fixed(t, x.decimals) << "</text>\n";
  }
  out << "<text x=\"" << fixed(kPlotRight, 1) << "\" y=\"" << fixed(y1 + 32.0, 1)
      << "\" text-anchor=\"end\" font-size=\"12\">t [s]</text>\n";
  out << "<text transform=\"translate(" << fixed(kPlotLeft - 58.0, 1) << "," << fixed((y0 + y1) / 2, 1)
      << ") rotate(-90)\" text-anchor=\"middle\" font-size=\"12\">" << escape_xml(q.name) << " [" << escape_xml(q.unit)
      << "]</text>\n";

  // Band and median, one piece per stretch of grid times that have samples.
  std::size_t k = 0;
  while (k < e.t_s.size()) {
    if (e.n[k] == 0) {
      ++k;
      continue;
    }
    std::size_t end = k;
    while (end < e.t_s.size() && e.n[end] > 0) ++end;
    if (end - k == 1) {
      out << "<circle cx=\"" << fixed(px(e.t_s[k]), 2) << "\" cy=\"" << fixed(py(e.p50[k]), 2)
          << "\" r=\"2.5\" fill=\"#08519c\"/>\n";
    } else {
      out << "<polygon fill=\"#9ecae1\" fill-opacity=\"0.7\" stroke=\"none\" points=\"";
      for (std::size_t i = k; i < end; ++i) out << (i == k ? "" : " ") << point(e.t_s[i], e.p95[i]);
      for (std::size_t i = end; i-- > k;) out << " " << point(e.t_s[i], e.p5[i]);
      out << "\"/>\n<polyline fill=\"none\" stroke=\"#08519c\" stroke-width=\"1.5\" points=\"";
      for (std::size_t i = k; i < end; ++i) out << (i == k ? "" : " ") << point(e.t_s[i], e.p50[i]);
      out << "\"/>\n";
    }
    k = end;
  }
  out << frame;
}

std::string set_svg(const SetReport& s, std::size_t index) {
  const bool traced = s.traces > 0 && !s.p.t_s.empty();
  const double height = traced ? kHeader + 3 * kPanelHeight : kHeader + 60.0;
  std::ostringstream out;
  out << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      << "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"" << fixed(kSvgWidth, 0) << "\" height=\""
      << fixed(height, 0) << "\" viewBox=\"0 0 " << fixed(kSvgWidth, 0) << " " << fixed(height, 0)
      << "\" font-family=\"sans-serif\">\n"
      << "<rect width=\"100%\" height=\"100%\" fill=\"white\"/>\n"
      << "<text x=\"10\" y=\"22\" font-size=\"16\" font-weight=\"bold\">Set " << index + 1 << ": "
      << escape_xml(s.label) << "</text>\n"
      << "<text x=\"10\" y=\"44\" font-size=\"13\">controlled " << s.controlled << "/" << s.runs << " = "
      << escape_xml(rate_text(s.rate)) << "; " << s.traces << " trace" << (s.traces == 1 ? "" : "s")
      << (traced ? "; band 5-95 % across runs, line median" : "") << "</text>\n";
  if (!traced) {
    out << "<text x=\"10\" y=\"" << fixed(kHeader + 30.0, 0)
        << "\" font-size=\"14\">no trace: no run of this set has a p, v, phi trace</text>\n";
  } else {
    const double t_end = s.p.t_s.back();
    const Axis x = nice_axis(0.0, t_end > 0.0 ? t_end : s.dt_s, 8);
    for (std::size_t q = 0; q < 3; ++q) {
      svg_panel(out, envelope_of(s, q), kQuantities[q], kHeader + static_cast<double>(q) * kPanelHeight, x);
    }
  }
  out << "</svg>\n";
  return out.str();
}

// --- the other files --------------------------------------------------------------------------

std::string envelopes_csv(const std::vector<SetReport>& sets) {
  std::string out = "set,label,quantity,unit,t_s,n,p5,p50,p95\n";
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const std::string head = std::to_string(s + 1) + "," + csv_quoted(sets[s].label) + ",";
    for (std::size_t q = 0; q < 3; ++q) {
      const Envelope& e = envelope_of(sets[s], q);
      for (std::size_t k = 0; k < e.t_s.size(); ++k) {
        out += head + kQuantities[q].name + "," + kQuantities[q].unit + "," + number(e.t_s[k]) + "," +
               std::to_string(e.n[k]) + "," + number(e.p5[k]) + "," + number(e.p50[k]) + "," + number(e.p95[k]) + "\n";
      }
    }
  }
  return out;
}

std::string report_json(const SweepResult& r, const std::vector<SetReport>& sets) {
  OrderedJson j = {{"scenario", r.scenario},
                   {"clock", r.clock},
                   {"confidence", 0.95},
                   {"percentiles", {5.0, 50.0, 95.0}},
                   {"sets", OrderedJson::array()}};
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const SetReport& st = sets[s];
    OrderedJson envelopes = OrderedJson::object();
    for (std::size_t q = 0; q < 3; ++q) {
      const Envelope& e = envelope_of(st, q);
      envelopes[kQuantities[q].name] = {
          {"unit", kQuantities[q].unit}, {"t_s", e.t_s}, {"n", e.n}, {"p5", e.p5}, {"p50", e.p50}, {"p95", e.p95}};
    }
    j["sets"].push_back({{"set", s + 1},
                         {"label", st.label},
                         {"runs", st.runs},
                         {"controlled", st.controlled},
                         {"controlled_rate", st.rate.p},
                         {"wilson_lo", st.rate.lo},
                         {"wilson_hi", st.rate.hi},
                         {"traces", st.traces},
                         {"dt_s", st.traces > 0 ? OrderedJson(st.dt_s) : OrderedJson(nullptr)},
                         {"svg", "set-" + std::to_string(s + 1) + ".svg"},
                         {"envelopes", std::move(envelopes)}});
  }
  return json_line(j) + "\n";
}

std::string index_html(const SweepResult& r, const std::vector<SetReport>& sets) {
  std::ostringstream out;
  int runs = 0;
  for (const auto& s : sets) runs += s.runs;
  out << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
      << "<title>rig sweep: " << escape_xml(r.scenario) << "</title>\n"
      << "<style>\nbody { font-family: sans-serif; margin: 1.5em; }\n"
      << "table { border-collapse: collapse; }\n"
      << "th, td { border: 1px solid #bbb; padding: 0.25em 0.6em; text-align: left; }\n"
      << "td.num { text-align: right; }\nimg { max-width: 100%; border: 1px solid #ddd; }\n</style>\n"
      << "</head>\n<body>\n<h1>rig sweep: " << escape_xml(r.scenario) << "</h1>\n"
      << "<p>Clock " << escape_xml(r.clock) << ", " << runs << " run" << (runs == 1 ? "" : "s") << " in " << sets.size()
      << " parameter set" << (sets.size() == 1 ? "" : "s")
      << ". Controlled rates with their 95 % Wilson score interval; envelopes across runs: median and "
      << "5 % and 95 % percentiles at each time. Data: <a href=\"envelopes.csv\">envelopes.csv</a>, "
      << "<a href=\"report.json\">report.json</a>.</p>\n"
      << "<table>\n<thead><tr><th>set</th><th>label</th><th>runs</th><th>controlled</th>"
      << "<th>controlled rate</th><th>95 % interval</th><th>traces</th></tr></thead>\n<tbody>\n";
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const SetReport& st = sets[s];
    out << "<tr><td class=\"num\"><a href=\"#set-" << s + 1 << "\">" << s + 1 << "</a></td><td>" << escape_xml(st.label)
        << "</td><td class=\"num\">" << st.runs << "</td><td class=\"num\">" << st.controlled
        << "</td><td class=\"num\">" << fixed(100.0 * st.rate.p, 1) << " %</td><td class=\"num\">"
        << fixed(100.0 * st.rate.lo, 1) << "-" << fixed(100.0 * st.rate.hi, 1) << " %</td><td class=\"num\">"
        << st.traces << "</td></tr>\n";
  }
  out << "</tbody>\n</table>\n";
  for (std::size_t s = 0; s < sets.size(); ++s) {
    const std::string k = std::to_string(s + 1);
    out << "<h2 id=\"set-" << k << "\">Set " << k << ": " << escape_xml(sets[s].label) << "</h2>\n"
        << "<p><img src=\"set-" << k << ".svg\" alt=\"p, v and phi across runs of set " << k << "\"></p>\n";
  }
  out << "</body>\n</html>\n";
  return out.str();
}

}  // namespace

std::vector<SetReport> sweep_report_sets(const SweepResult& result) {
  std::vector<SetReport> sets(result.sets.size());
  std::vector<std::vector<const RunTrace*>> traces(result.sets.size());
  for (std::size_t s = 0; s < sets.size(); ++s) sets[s].label = result.sets[s].label;
  for (const SweepRun& run : result.runs) {
    if (run.set >= sets.size()) {
      throw std::invalid_argument("sweep report: a run (seed " + std::to_string(run.seed) + ") names parameter set " +
                                  std::to_string(run.set + 1) + " of " + std::to_string(sets.size()));
    }
    SetReport& st = sets[run.set];
    ++st.runs;
    st.controlled += run.controlled ? 1 : 0;
    if (samples(run.trace) == 0) continue;
    const std::string which = "parameter set " + std::to_string(run.set + 1) + " '" + st.label + "'";
    if (!(run.trace.dt_s > 0.0) || !std::isfinite(run.trace.dt_s)) {
      throw std::invalid_argument("sweep report: the trace of seed " + std::to_string(run.seed) + " in " + which +
                                  " has samples but no positive dt_s (" + number(run.trace.dt_s) + ")");
    }
    if (st.traces > 0 && run.trace.dt_s != st.dt_s) {
      throw std::invalid_argument("sweep report: the traces of " + which + " have different dt_s (" + number(st.dt_s) +
                                  " s and " + number(run.trace.dt_s) + " s at seed " + std::to_string(run.seed) + ")");
    }
    st.dt_s = run.trace.dt_s;
    ++st.traces;
    traces[run.set].push_back(&run.trace);
  }
  for (std::size_t s = 0; s < sets.size(); ++s) {
    SetReport& st = sets[s];
    st.rate = wilson(st.controlled, st.runs);
    std::size_t grid = 0;
    for (const RunTrace* t : traces[s]) grid = std::max(grid, samples(*t));
    st.p = envelope(traces[s], grid, st.dt_s, &RunTrace::p, 1.0);
    st.v = envelope(traces[s], grid, st.dt_s, &RunTrace::v, 1.0);
    st.phi_deg = envelope(traces[s], grid, st.dt_s, &RunTrace::phi, kDegPerRad);
  }
  return sets;
}

void write_sweep_report(const SweepResult& result, const std::string& dir) {
  const std::vector<SetReport> sets = sweep_report_sets(result);
  std::vector<std::pair<std::string, std::string>> files;
  files.emplace_back("envelopes.csv", envelopes_csv(sets));
  files.emplace_back("report.json", report_json(result, sets));
  for (std::size_t s = 0; s < sets.size(); ++s) {
    files.emplace_back("set-" + std::to_string(s + 1) + ".svg", set_svg(sets[s], s));
  }
  files.emplace_back("index.html", index_html(result, sets));

  if (dir.empty()) throw std::runtime_error("cannot write the sweep report: no directory given");
  std::error_code ec;
  fs::create_directories(dir, ec);
  const bool made = !ec && fs::is_directory(dir, ec);
  if (!made) {
    throw std::runtime_error("cannot make the sweep report directory " + dir + ": " +
                             (ec ? ec.message() : std::string("not a directory")));
  }
  for (const auto& file : files) write_file(fs::path(dir) / file.first, file.second);
}

}  // namespace nimble::campaign
