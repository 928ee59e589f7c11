/// The verdict of one cell of `rig reproduce thesis` (reproduce/cell_verdict.h).

#include "reproduce/cell_verdict.h"

#include <algorithm>
#include <cmath>

#include <fmt/format.h>

namespace nimble::reproduce {
namespace {

/// Student t quantile 0.975 for 1..30 degrees of freedom (standard tables); 1.96 beyond.
double t975(int dof) {
  static const double kT[] = {12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
                              2.201,  2.179, 2.160, 2.145, 2.131, 2.120, 2.110, 2.101, 2.093, 2.086,
                              2.080,  2.074, 2.069, 2.064, 2.060, 2.056, 2.052, 2.048, 2.045, 2.042};
  if (dof < 1) return NAN;
  return dof <= 30 ? kT[dof - 1] : 1.96;
}

std::string join(const std::vector<std::string>& v) {
  std::string s;
  for (const auto& x : v) s += (s.empty() ? "" : ", ") + x;
  return s;
}

}  // namespace

double half_last_digit(double value) {
  // Relative to the scaled value itself: 1.44e-7 has its last digit at 1e-9, not at 1.
  for (int d = 0; d <= 15; ++d) {
    const double scaled = value * std::pow(10.0, d);
    if (std::fabs(scaled - std::round(scaled)) < 1e-6 * std::fabs(scaled)) return 0.5 * std::pow(10.0, -d);
  }
  return 0.0;
}

int seeds_to_decide(double sd, double distance) {
  if (!(distance > 0.0) || !std::isfinite(sd)) return 0;
  if (sd == 0.0) return 2;
  for (int n = 2; n <= 1000000; n = n < 64 ? n + 1 : n + n / 8) {
    if (t975(n - 1) * sd / std::sqrt(static_cast<double>(n)) < distance) return n;
  }
  return 0;
}

const char* category_name(Category c) {
  switch (c) {
    case Category::kFlights: return "flights";
    case Category::kCalibrated: return "calibrated";
    case Category::kModel: return "model";
  }
  return "?";
}

const Reason* TableSpec::reason_for(const std::string& cell) const {
  for (const Reason& r : reasons) {
    if (std::find(r.cells.begin(), r.cells.end(), cell) != r.cells.end()) return &r;
  }
  return nullptr;
}

void mean_interval(const std::vector<double>& x, double* mean, double* sd, double* half_width) {
  const int n = static_cast<int>(x.size());
  double m = 0.0;
  for (double v : x) m += v;
  m = n > 0 ? m / n : NAN;
  double ss = 0.0;
  for (double v : x) ss += (v - m) * (v - m);
  const double s = n > 1 ? std::sqrt(ss / (n - 1)) : 0.0;
  *mean = m;
  *sd = s;
  *half_width = n > 1 ? t975(n - 1) * s / std::sqrt(static_cast<double>(n)) : 0.0;
}

namespace {

/// Half a unit of the last digit of the published number as the campaign file writes it.
double printed_half(const TableSpec& t, const std::string& row, const std::string& column, double published) {
  if (const auto r = t.printed_half_digit.find(row); r != t.printed_half_digit.end()) {
    if (const auto h = r->second.find(column); h != r->second.end()) return h->second;
  }
  return half_last_digit(published);
}

/// The cell's tolerance and its basis. A pipeline check: half the published number's last digit.
/// Otherwise the thesis's sigma where it gives one, else absolute by column, else relative; never
/// tighter than half the published number's last digit.
void set_tolerance(const TableSpec& t, const std::string& row, const std::string& column, Cell& c) {
  const std::string key = row + " / " + column;
  const double half_digit = printed_half(t, row, column, c.published);
  if (!t.reference_table.empty()) {
    c.tolerance = half_digit;
    c.tolerance_basis = fmt::format(
        "half the published number's last digit, {:g}: the pipeline's error must not show "
        "in the number as the thesis prints it",
        half_digit);
    return;
  }
  if (const auto s = t.thesis_sigma.find(key); s != t.thesis_sigma.end() && t.thesis_sigmas > 0) {
    c.tolerance = t.thesis_sigmas * s->second;
    c.tolerance_basis = fmt::format("{:g} x the thesis's sigma {:.3g}", t.thesis_sigmas, s->second);
  } else if (const auto a = t.absolute.find(column); a != t.absolute.end()) {
    c.tolerance = a->second;
    c.tolerance_basis = fmt::format("{:g} absolute", a->second);
  } else {
    c.tolerance = t.relative * std::fabs(c.published);
    c.tolerance_basis = fmt::format("{:g} % of the published value", 100 * t.relative);
  }
  // A printed number carries its rounding: no tolerance is tighter than half its last digit.
  if (c.tolerance < half_digit) {
    c.tolerance = half_digit;
    c.tolerance_basis += fmt::format(", raised to half the printed last digit, {:g}", half_digit);
  }
}

/// Each part of a reason's predicate on the cell (`off` = rig - published), in words (`parts`)
/// and as found (`found`); true if every part holds.
bool reason_holds(const Reason& r, double off, const Cell& c, const JudgeContext& context,
                  std::vector<std::string>& parts, std::vector<std::string>& found) {
  const Reason* why = &r;
  bool holds = true;
  if (!why->rig.empty()) {
    parts.push_back("rig " + why->rig + " published");
    const bool ok = why->rig == "above" ? off > 0 : off < 0;
    found.push_back(fmt::format("rig {} published by {:.3g}", off > 0 ? "above" : "below", std::fabs(off)));
    holds = holds && ok;
  }
  if (why->max_off >= 0) {
    parts.push_back(fmt::format("|rig - published| <= {:g}", why->max_off));
    holds = holds && std::fabs(off) <= why->max_off;
    // A bound far above the gap cannot fail: it describes nothing of this cell.
    if (why->max_off > kMaxOffPerGap * std::fabs(off)) {
      found.push_back(fmt::format("the bound {:g} is over {:g} times the cell's gap {:.3g}: it cannot fail",
                                  why->max_off, kMaxOffPerGap, std::fabs(off)));
      holds = false;
    }
  }
  if (!why->states.empty()) {
    parts.push_back("states from " + join(why->states));
    const bool ok = std::find(why->states.begin(), why->states.end(), context.states) != why->states.end();
    found.push_back("states from " + context.states);
    holds = holds && ok;
  }
  if (why->with.empty()) {
    // Direction, bound and states describe a difference; only a cause flown in the same run,
    // which moves the cell, explains it.
    parts.push_back("a cause flown in this run (with:) that moves the cell");
    found.push_back("the reason names no cause to fly: it describes the difference, it does not explain it");
    holds = false;
  } else {
    std::vector<std::string> set;
    for (const auto& [k, v] : why->with) set.push_back(k + "=" + v);
    parts.push_back(fmt::format("with {} the cell moves {} the published value by >= {:g} of the gap", join(set),
                                why->moves, why->at_least));
    if (context.with_values.empty()) {
      found.push_back("the flight with the cause was not flown");
      holds = false;
    } else if (!context.with_failure.empty()) {
      found.push_back("the flight with the cause did not fly as its scenario asks: " + context.with_failure);
      holds = false;
    } else {
      double m = 0, sd = 0, hw = 0;
      mean_interval(context.with_values, &m, &sd, &hw);
      const double gap = std::fabs(off);
      const double moved = gap - std::fabs(m - c.published);  // > 0: toward
      const double share = gap > 0 ? moved / gap : 0.0;
      const bool ok = why->moves == "toward" ? share >= why->at_least : -share >= why->at_least;
      const bool past = (m - c.published) * off < 0;  // crossed the published value
      found.push_back(past ? fmt::format("with the cause {:.4g}, past the published value by {:.0f} % of the gap", m,
                                         100 * std::fabs(m - c.published) / gap)
                           : fmt::format("with the cause {:.4g} (moved {:.0f} % of the gap {})", m,
                                         100 * std::fabs(share), share >= 0 ? "toward" : "away"));
      holds = holds && ok;
    }
  }
  return holds;
}

}  // namespace

Cell judge(const TableSpec& t, const std::string& row, const std::string& column, const std::vector<double>& rig,
           const JudgeContext& context) {
  Cell c;
  c.row = row;
  c.column = column;
  c.published = t.published.at(row).at(column);
  c.seeds = static_cast<int>(rig.size());
  mean_interval(rig, &c.rig, &c.rig_sd, &c.interval);
  const std::string key = row + " / " + column;
  const bool calibrated =
      std::find(t.calibrated_cells.begin(), t.calibrated_cells.end(), key) != t.calibrated_cells.end();
  const Category category = calibrated ? Category::kCalibrated : t.category;
  c.category = category_name(category);
  c.values = rig;
  const bool pipeline = !t.reference_table.empty();
  c.reference = pipeline ? context.reference : c.published;
  set_tolerance(t, row, column, c);
  if (pipeline && !std::isfinite(c.reference)) {
    c.verdict = "differs";
    c.reason = "the plant file gives no value to judge the pipeline against";
    return c;
  }
  // A band that holds zero and the value's opposite cannot fail: no verdict.
  if (!(c.tolerance < std::fabs(c.reference))) {
    c.verdict = "not judged";
    c.reason = fmt::format(
        "the tolerance {:.3g} ({}) is as wide as the value {:g} itself: no comparison with it could "
        "fail",
        c.tolerance, c.tolerance_basis, c.reference);
    return c;
  }
  const double off = c.rig - c.reference;
  if (!std::isfinite(c.rig)) {
    c.verdict = "differs";
    c.reason = "the rig has no value";
    return c;
  }
  const int min_seeds = pipeline ? kPipelineMinSeeds : category == Category::kFlights ? t.min_seeds : 1;
  if (c.seeds < min_seeds) {
    c.verdict = "inconclusive";
    c.reason = fmt::format("judged on the mean of at least {} seeds; {} flown", min_seeds, c.seeds);
    return c;
  }
  // Equivalence by two one-sided tests: the mean's 95 % interval inside the tolerance band is a
  // match, wholly outside it a difference, across an edge neither.
  const double lo = c.rig - c.interval, hi = c.rig + c.interval;
  const double band_lo = c.reference - c.tolerance, band_hi = c.reference + c.tolerance;
  if (lo >= band_lo && hi <= band_hi) {
    c.verdict = "match";
    if (calibrated) c.reason = t.calibrated_why;
    return c;
  }
  if (lo <= band_hi && hi >= band_lo) {
    c.verdict = "inconclusive";
    c.seeds_to_decide = seeds_to_decide(c.rig_sd, std::min(std::fabs(c.rig - band_lo), std::fabs(c.rig - band_hi)));
    c.reason =
        fmt::format("the rig's interval {:.4g} +- {:.3g} ({} seeds) crosses an edge of the band {:.4g} +- {:.3g}; ",
                    c.rig, c.interval, c.seeds, c.reference, c.tolerance) +
        (c.seeds_to_decide > 0 ? fmt::format("about {} seeds would decide it", c.seeds_to_decide)
                               : std::string("no number of seeds decides it (the mean sits on the edge)"));
    return c;
  }
  const Reason* why = category == Category::kFlights ? t.reason_for(key) : nullptr;
  if (why == nullptr) {
    c.verdict = "differs";
    c.reason = fmt::format("off by {:.3g}{}, allowed {:.3g}", off, pipeline ? " from the plant file's value" : "",
                           c.tolerance);
    return c;
  }
  std::vector<std::string> parts, found;
  const bool holds = reason_holds(*why, off, c, context, parts, found);
  c.has_check = true;
  c.check.predicate = parts.empty() ? "(none)" : join(parts);
  c.check.holds = holds && !parts.empty();
  c.check.value = join(found);
  if (c.check.holds) {
    c.verdict = "explained";
    c.reason = why->text;
  } else {
    c.verdict = "differs";
    c.reason = fmt::format("off by {:.3g}, allowed {:.3g}; the reason's check fails: {} (found: {})", off, c.tolerance,
                           c.check.predicate, c.check.value);
  }
  return c;
}

}  // namespace nimble::reproduce
