#include "detection_power/power_report.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <map>
#include <sstream>

#include "core/output_file.h"
#include "ident/plots.h"
#include "plots/gnuplot.h"
#include "core/json_line.h"

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

OrderedJson proportion_json(const Proportion& p) {
  return {{"count", p.count}, {"n", p.n}, {"p", p.p}, {"lo", p.lo}, {"hi", p.hi}};
}

OrderedJson cell_json(const PowerCell& c) {
  const double n = std::max<double>(1.0, static_cast<double>(c.flights.size()));
  OrderedJson other_names = OrderedJson::object(), verdicts = OrderedJson::object();
  for (const auto& [name, count] : c.other_names) other_names[name] = count;
  for (const auto& [verdict, count] : c.verdicts) verdicts[verdict] = count;
  return {{"size", c.size},
          {"length_s", c.length_s},
          {"repetitions", c.repetitions},
          {"kind", c.kind},
          {"flights", c.flights.size()},
          {"named", proportion_json(c.named)},
          {"other", proportion_json(c.other)},
          {"alarm", proportion_json(c.alarm)},
          {"other_names", std::move(other_names)},
          {"verdicts", std::move(verdicts)},
          {"not_ok", c.not_ok},
          {"failed", c.failed},
          {"flight_s_mean", c.flight_s / n},
          {"workflow_s_mean", c.workflow_s / n},
          {"flight_cpu_s_mean", c.flight_cpu_s / n},
          {"workflow_cpu_s_mean", c.workflow_cpu_s / n}};
}

/// Where a curve reaches the target: `what` at `at`, and `value_key` where it is reached (null if not).
OrderedJson crossing_json(const char* what, double at, const char* value_key, const Crossing& rec) {
  return {{what, at}, {"reached", rec.reached}, {value_key, rec.value}, {"note", rec.note}};
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
  OrderedJson j = {{"scenario", r.scenario},   {"model", r.model},   {"effect", r.effect},
                   {"parameter", r.parameter}, {"unit", r.unit},     {"named_as", r.named_as},
                   {"block_s", r.block_s},     {"target", r.target}, {"flights_per_cell", r.flights},
                   {"seed", r.seed},           {"jobs", r.jobs},     {"sizes", r.sizes},
                   {"lengths_s", r.lengths_s}};
  j["cells"] = OrderedJson::array();
  for (const PowerCell& c : r.cells) j["cells"].push_back(cell_json(c));
  j["recommended_length"] = OrderedJson::array();
  for (const SizeCurve& c : r.curves)
    j["recommended_length"].push_back(crossing_json("size", c.size, "length_s", c.length));
  j["smallest_size"] = OrderedJson::array();
  for (std::size_t l = 0; l < r.lengths_s.size(); ++l) {
    j["smallest_size"].push_back(crossing_json("length_s", r.lengths_s[l], "size", r.size_for_length[l]));
  }
  j["verification"] = OrderedJson::array();
  for (const PowerCell& c : r.verification) j["verification"].push_back(cell_json(c));
  const Totals t = totals(r);
  const double n = std::max<double>(1.0, static_cast<double>(t.flights));
  j["timing"] = {{"wall_s", r.wall_s},
                 {"setup_s", r.setup_s},
                 {"flights", t.flights},
                 {"flight_s_mean", t.flight_s / n},
                 {"build_s_mean", t.build_s / n},
                 {"workflow_s_mean", t.workflow_s / n},
                 {"flight_cpu_s_mean", t.flight_cpu_s / n},
                 {"workflow_cpu_s_mean", t.workflow_cpu_s / n}};
  j["plots"] = plots;
  return json_line(j);
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
