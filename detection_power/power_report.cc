#include "detection_power/power_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/json_writer.h"
#include "core/output_file.h"
#include "ident/plots.h"
#include "plots/gnuplot.h"

namespace nimble::detection_power {
namespace {

namespace fs = std::filesystem;
const char* const kColours[] = {"#1f77b4", "#d62728", "#2ca02c", "#9467bd", "#ff7f0e", "#8c564b", "#17becf"};

std::string colour(std::size_t i) { return kColours[i % (sizeof kColours / sizeof kColours[0])]; }

std::string num(double x, const char* format = "%.4g") {
  char text[48];
  std::snprintf(text, sizeof text, format, x);
  return text;
}

std::string cell_text(const Proportion& p) {
  return num(100 * p.p, "%.0f") + " [" + num(100 * p.lo, "%.0f") + "," + num(100 * p.hi, "%.0f") + "]";
}

/// One size's cells by length: the naming probability, another name, any alarm, runs not ok.
void size_block(std::ostringstream& out, const PowerResult& r, const SizeCurve& curve) {
  char line[200];
  out << "\n"
      << r.parameter << " = " << num(curve.size) << " " << r.unit
      << (curve.size == 0.0 ? " (the effect off: naming it is a false name)" : "") << "\n";
  std::snprintf(line, sizeof line, "  %10s %7s %9s  %-18s %-18s %-18s %s\n", "length [s]", "blocks", "", "named, %",
                "another name, %", "any alarm, %", "not ok");
  out << line;
  for (const std::size_t i : curve.cells) {
    const PowerCell& c = r.cells[i];
    std::snprintf(line, sizeof line, "  %10s %7.2f %9s  %-18s %-18s %-18s %d\n", num(c.length_s).c_str(),
                  c.length_s / r.block_s, c.kind == "grid" ? "" : c.kind.c_str(), cell_text(c.named).c_str(),
                  cell_text(c.other).c_str(), cell_text(c.alarm).c_str(), c.not_ok + c.failed);
    out << line;
  }
  const Crossing& rec = curve.length;
  if (curve.size != 0.0) {
    out << "  -> " << num(100 * r.target, "%.0f") << " %: "
        << (rec.reached
                ? num(rec.value, "%.2f") + " s, " + num(rec.value / r.block_s, "%.2f") + " blocks (" + rec.note + ")"
                : rec.note)
        << "\n";
  }
}

void proportion_json(JsonWriter& w, const std::string& key, const Proportion& p) {
  w.key(key).begin_object();
  w.key("count").value(p.count).key("n").value(p.n).key("p").value(p.p).key("lo").value(p.lo).key("hi").value(p.hi);
  w.end_object();
}

void cell_json(JsonWriter& w, const PowerCell& c) {
  w.begin_object();
  w.key("size").value(c.size).key("length_s").value(c.length_s).key("repetitions").value(c.repetitions);
  w.key("kind").value(c.kind);
  w.key("flights").value(static_cast<long long>(c.flights.size()));
  proportion_json(w, "named", c.named);
  proportion_json(w, "other", c.other);
  proportion_json(w, "alarm", c.alarm);
  w.key("other_names").begin_object();
  for (const auto& [name, count] : c.other_names) w.key(name).value(count);
  w.end_object();
  w.key("verdicts").begin_object();
  for (const auto& [verdict, count] : c.verdicts) w.key(verdict).value(count);
  w.end_object();
  w.key("not_ok").value(c.not_ok).key("failed").value(c.failed);
  const double n = std::max<double>(1.0, static_cast<double>(c.flights.size()));
  w.key("flight_s_mean").value(c.flight_s / n).key("workflow_s_mean").value(c.workflow_s / n);
  w.key("flight_cpu_s_mean").value(c.flight_cpu_s / n).key("workflow_cpu_s_mean").value(c.workflow_cpu_s / n);
  w.end_object();
}

void crossing_json(JsonWriter& w, const char* what, double at, const char* value_key, const Crossing& rec) {
  w.begin_object();
  w.key(what).value(at).key("reached").value(rec.reached).key(value_key);
  if (std::isfinite(rec.value)) {
    w.value(rec.value);
  } else {
    w.null();
  }
  w.key("note").value(rec.note);
  w.end_object();
}

struct Totals {
  std::size_t flights = 0;
  double flight_s = 0.0, build_s = 0.0, workflow_s = 0.0, flight_cpu_s = 0.0, workflow_cpu_s = 0.0;
};

Totals totals(const PowerResult& r) {
  Totals t;
  for (const auto* cells : {&r.cells, &r.verification}) {
    for (const PowerCell& c : *cells) {
      t.flights += c.flights.size();
      t.flight_s += c.flight_s;
      t.build_s += c.build_s;
      t.workflow_s += c.workflow_s;
      t.flight_cpu_s += c.flight_cpu_s;
      t.workflow_cpu_s += c.workflow_cpu_s;
    }
  }
  return t;
}

}  // namespace

std::string power_text(const PowerResult& r) {
  std::ostringstream out;
  out << "== how long to fly: " << r.effect << " on " << r.scenario << " ==\n";
  out << "SIZE sets plant.effects." << r.effect << "." << r.parameter << " [" << r.unit << "]; the workflow (model "
      << r.model << ") names it " << r.named_as << "\n";
  out << "record: the scenario's block of " << num(r.block_s) << " s (its manoeuvre and hover) flown again and again, "
      << "cut at the length\n";
  out << r.flights << " flights per cell (campaign seed " << r.seed << ", the same seeds in every cell), " << r.jobs
      << " job" << (r.jobs == 1 ? "" : "s") << "\n";
  out << "per cell: % of flights [95 % Wilson interval]; the target crossing by probit against sqrt(length) between\n"
      << "the lengths that bracket it\n";
  for (const SizeCurve& curve : r.curves) size_block(out, r, curve);
  std::map<std::string, int> others, verdicts;
  std::size_t flights = 0;
  for (const PowerCell& c : r.cells) {
    for (const auto& [name, count] : c.other_names) others[name] += count;
    for (const auto& [verdict, count] : c.verdicts) verdicts[verdict] += count;
    flights += c.flights.size();
  }
  out << "\nover all " << flights << " flights: verdicts";
  for (const auto& [verdict, count] : verdicts) out << " " << verdict << " " << count;
  out << "; other names";
  for (const auto& [name, count] : others) out << " " << name << " " << count;
  out << (others.empty() ? " none\n" : "\n");
  out << "\nsmallest size named with " << num(100 * r.target, "%.0f") << " % (probit against |size|):\n";
  for (std::size_t l = 0; l < r.lengths_s.size(); ++l) {
    const Crossing& rec = r.size_for_length[l];
    out << "  length " << num(r.lengths_s[l])
        << " s: " << (rec.reached ? num(rec.value) + " (" + rec.note + ")" : rec.note) << "\n";
  }
  for (const PowerCell& c : r.verification) {
    out << "verification, fresh seeds: size " << num(c.size) << " at " << num(c.length_s) << " s: named "
        << c.named.count << "/" << c.named.n << " = " << num(100 * c.named.p, "%.1f") << " % ["
        << num(100 * c.named.lo, "%.1f") << ", " << num(100 * c.named.hi, "%.1f") << "], another name "
        << num(100 * c.other.p, "%.1f") << " %, any alarm " << num(100 * c.alarm.p, "%.1f") << " %\n";
  }
  const Totals t = totals(r);
  const double n = std::max<double>(1.0, static_cast<double>(t.flights));
  out << "\ntime: " << t.flights << " flights in " << num(r.wall_s, "%.1f") << " s wall on " << r.jobs << " job"
      << (r.jobs == 1 ? "" : "s") << " (plans " << num(r.setup_s, "%.2f") << " s)\n"
      << "per flight: flying " << num(t.flight_s / n, "%.3f") << " s wall, " << num(t.flight_cpu_s / n, "%.3f")
      << " s CPU (building the processes " << num(t.build_s / n, "%.3f") << " s wall); workflow "
      << num(t.workflow_s / n, "%.3f") << " s wall, " << num(t.workflow_cpu_s / n, "%.3f") << " s CPU\n";
  return out.str();
}

std::string power_json(const PowerResult& r, const std::vector<std::string>& plots) {
  JsonWriter w;
  w.begin_object();
  w.key("scenario").value(r.scenario).key("model").value(r.model).key("effect").value(r.effect);
  w.key("parameter").value(r.parameter).key("unit").value(r.unit).key("named_as").value(r.named_as);
  w.key("block_s").value(r.block_s).key("target").value(r.target).key("flights_per_cell").value(r.flights);
  w.key("seed").value(static_cast<long long>(r.seed)).key("jobs").value(r.jobs);
  w.key("sizes").array(r.sizes).key("lengths_s").array(r.lengths_s);
  w.key("cells").begin_array();
  for (const PowerCell& c : r.cells) cell_json(w, c);
  w.end_array();
  w.key("recommended_length").begin_array();
  for (const SizeCurve& c : r.curves) crossing_json(w, "size", c.size, "length_s", c.length);
  w.end_array();
  w.key("smallest_size").begin_array();
  for (std::size_t l = 0; l < r.lengths_s.size(); ++l) {
    crossing_json(w, "length_s", r.lengths_s[l], "size", r.size_for_length[l]);
  }
  w.end_array();
  w.key("verification").begin_array();
  for (const PowerCell& c : r.verification) cell_json(w, c);
  w.end_array();
  const Totals t = totals(r);
  const double n = std::max<double>(1.0, static_cast<double>(t.flights));
  w.key("timing").begin_object();
  w.key("wall_s").value(r.wall_s).key("setup_s").value(r.setup_s).key("flights").value(
      static_cast<long long>(t.flights));
  w.key("flight_s_mean").value(t.flight_s / n).key("build_s_mean").value(t.build_s / n);
  w.key("workflow_s_mean").value(t.workflow_s / n);
  w.key("flight_cpu_s_mean").value(t.flight_cpu_s / n).key("workflow_cpu_s_mean").value(t.workflow_cpu_s / n);
  w.end_object();
  w.key("plots").array(plots);
  w.end_object();
  return w.str();
}

std::vector<std::string> write_power_plots(const PowerResult& r, const std::string& dir_text) {
  plots::require_gnuplot();
  const fs::path dir(dir_text);
  fs::create_directories(dir);
  std::vector<std::string> pngs;
  const std::string target = "set arrow from graph 0, first " + num(r.target) + " to graph 1, first " + num(r.target) +
                             " nohead dt 2 lc rgb '#555555'\n";
  // Against the length: one block of rows per size (x, p, lo, hi), gnuplot's index selects it.
  {
    std::ostringstream data, script;
    for (const SizeCurve& curve : r.curves) {
      data << "# size " << curve.size << "\n";
      for (const std::size_t i : curve.cells) {
        const Proportion& p = r.cells[i].named;
        data << r.cells[i].length_s << " " << p.p << " " << p.lo << " " << p.hi << "\n";
      }
      data << "\n\n";
    }
    write_file(dir / "power_length.dat", data.str());
    script << "set terminal pngcairo noenhanced size 1000,650\nset output "
           << plots::gp_quote((dir / "power_length.png").string()) << "\n"
           << "set title "
           << plots::gp_quote("P(" + r.named_as + " named) on " + r.scenario + ", " + std::to_string(r.flights) +
                              " flights per point, 95 % Wilson intervals")
           << "\nset xlabel 'record length [s]'\nset ylabel 'probability'\nset yrange [0:1.05]\nset grid\n"
           << "set key bottom right\n"
           << target;
    for (std::size_t s = 0; s < r.curves.size(); ++s) {
      const Crossing& rec = r.curves[s].length;
      if (!rec.reached || r.curves[s].size == 0.0) continue;
      script << "set arrow from " << rec.value << ", graph 0 to " << rec.value << ", first " << r.target
             << " nohead dt 3 lc rgb '" << colour(s) << "'\n";
    }
    script << "plot ";
    for (std::size_t s = 0; s < r.sizes.size(); ++s) {
      script << (s ? ", " : "") << plots::gp_quote((dir / "power_length.dat").string()) << " index " << s
             << " using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '" << colour(s) << "' title "
             << plots::gp_quote(r.parameter + " = " + num(r.sizes[s]) + " " + r.unit);
    }
    script << "\n";
    plots::run_gnuplot(dir, "power_length", script.str());
    pngs.push_back((dir / "power_length.png").string());
  }
  // Against |size|: one block per length.
  {
    std::ostringstream data, script;
    for (std::size_t l = 0; l < r.lengths_s.size(); ++l) {
      data << "# length " << r.lengths_s[l] << " s\n";
      std::vector<std::size_t> order;
      for (std::size_t s = 0; s < r.sizes.size(); ++s) order.push_back(s);
      std::sort(order.begin(), order.end(),
                [&](std::size_t a, std::size_t b) { return std::fabs(r.sizes[a]) < std::fabs(r.sizes[b]); });
      for (const std::size_t s : order) {
        const Proportion& p = r.cell(s, l).named;
        data << std::fabs(r.sizes[s]) << " " << p.p << " " << p.lo << " " << p.hi << "\n";
      }
      data << "\n\n";
    }
    write_file(dir / "power_size.dat", data.str());
    script << "set terminal pngcairo noenhanced size 1000,650\nset output "
           << plots::gp_quote((dir / "power_size.png").string()) << "\n"
           << "set title " << plots::gp_quote("P(" + r.named_as + " named) on " + r.scenario + " against the size")
           << "\nset xlabel " << plots::gp_quote("|" + r.parameter + "| [" + r.unit + "]")
           << "\nset ylabel 'probability'\nset yrange [0:1.05]\nset grid\nset key bottom right\n"
           << target << "plot ";
    for (std::size_t l = 0; l < r.lengths_s.size(); ++l) {
      script << (l ? ", " : "") << plots::gp_quote((dir / "power_size.dat").string()) << " index " << l
             << " using 1:2:3:4 with yerrorlines lw 2 pt 7 lc rgb '" << colour(l) << "' title "
             << plots::gp_quote("length " + num(r.lengths_s[l]) + " s");
    }
    script << "\n";
    plots::run_gnuplot(dir, "power_size", script.str());
    pngs.push_back((dir / "power_size.png").string());
  }
  return pngs;
}

}  // namespace nimble::detection_power
