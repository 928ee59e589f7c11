// The discrepancy workflow's power against the best possible test: the one that knows the true
// form (the oracle). A measurement, not a test.
//
// Records come from tests/ident/discrepancy_generator_open.h, a generator independent of
// discrepancy_generator.h (on whose records the workflow's own suites were built): random 3-2-1-1
// multisteps, doublets and steps with hover gaps instead of a regular doublet train, a digital
// roll PID with drawn gains, coloured process noise and drawn measurement noise. Each record hides
// one form at a size (1 = the form's reference magnitude); the workflow runs with its defaults
// and, beside its search, tests the true form once on the model as given
// (DiscrepancyOptions::test_terms). The oracle detects when that one test's p-value is at most
// alpha (default 0.01); the workflow detects when its verdict is anything but `none`, and is
// right when it names the form: a `term` in the oracle's equation with the oracle's operator and
// signals (its number, scanned, may differ), or for inflow_other_arm the library's lateral_inflow.
//
// Printed per form and size: records, oracle detections (nominal; calibrated, or.cal; and
// instrumented by the excitation, or.iv: instrumented_wald at alpha), workflow detections, the right form,
// another term, a library name (a wrong name, listed), ambiguous, unexplained, a side gust alone,
// none, and right form / oracle detections. Per form: the oracle's 90 %-power size (the smallest
// grid size where the oracle detects at least 90 %) and the right-form rate over the records at
// that size and above (target at least 80 %), with Wilson 95 % intervals. Null records (no form):
// every alarm of the workflow, and the oracle's own rejection rate per oracle term at alpha, least
// squares and instrumented, with the mean and spread of coefficient / sigma (a mean away from 0 is
// the test's bias, a spread above 1 a variance it underestimates).
// Records whose loop diverged are refused by the generator, counted and replaced.
//
// The oracle's own null rate is not alpha: one test of a form beside the model's refit
// derivatives, on closed-loop data, rejects more often than its nominal level (measured on both
// generators' nulls, --reference-nulls). The nulls run first, and column or.cal counts the
// oracle at its level measured on them (per form, below the (floor(alpha M) + 1)-th smallest null
// p-value), beside the nominal column oracle.
//
//   build/bin/bench_discrepancy_oracle [--records N] [--nulls M] [--forms a,b] [--sizes x,y,...]
//                                      [--alpha A] [--json FILE] [--verbose]
// Defaults: 10 records per form and size (15-45 s, model sets 1-5, seeds 700000 + 10000 form +
// 1000 size + record), each form's own size grid (discrepancy_generator_open.h form_specs()), 200
// nulls (seeds from 800000); a refused record's next try adds 1000000 to its seed. About 6 min.
// Diagnostics: --oracle-only (the library search cut to one candidate, no term search: the oracle
// alone, fast, for placing a grid), --corner-hz F and --measurement-noise K (the nulls' process
// noise at another corner, the measurement noise scaled), --reference-nulls (the nulls from
// discrepancy_generator.h instead); --process-noise K (the process noise scaled), --cutoff-hz F
// (the workflow's low-pass at F Hz; negative: none) and --heldout-sigmas S (the held-out rule's
// sigmas), to find where the least-squares oracle's bias comes from and what a rule costs.

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <map>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "core/proportion.h"
#include "discrepancy_generator.h"
#include "discrepancy_generator_open.h"
#include "discrepancy/discrepancy.h"

using namespace nimble;
using namespace nimble::ident;
namespace gen = nimble::ident::test_open;

namespace {

struct Args {
  int records = 10, nulls = 200;
  std::vector<std::string> forms;
  std::vector<double> sizes;
  double alpha = 0.01;
  std::string json;
  bool verbose = false;
  bool oracle_only = false;  ///< the oracle alone (the library's search cut short, no term search): placing the grid
  /// Diagnostics of the nulls: every record's process-noise corner at this frequency [Hz] (its
  /// standard deviation scaled by sqrt(corner / drawn corner), which keeps the level below the
  /// corners), and the measurement noise times this factor. 0 and 1: as drawn.
  double corner_hz = 0.0, measurement_noise = 1.0;
  double process_noise = 1.0;    ///< Diagnostic: the process noise's standard deviations times this factor.
  double cutoff_hz = 0.0;        ///< Diagnostic: the workflow's low-pass cut-off (0: its default).
  double heldout_sigmas = -1.0;  ///< Diagnostic: DiscrepancyOptions::heldout_sigmas (negative: its default).
  /// Diagnostic: the nulls from the suite's own generator (discrepancy_generator.h, no effect), to
  /// tell the oracle's null rate on these records from its rate on those.
  bool reference_nulls = false;
};

std::vector<std::string> split(const std::string& s) {
  std::vector<std::string> out;
  std::stringstream in(s);
  for (std::string item; std::getline(in, item, ',');)
    if (!item.empty()) out.push_back(item);
  return out;
}

Args parse_args(int argc, char** argv) {
  Args a;
  for (int i = 1; i < argc; ++i) {
    const std::string k = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) {
        std::fprintf(stderr, "bench_discrepancy_oracle: %s needs a value\n", k.c_str());
        std::exit(2);
      }
      return argv[++i];
    };
    if (k == "--records")
      a.records = std::atoi(value().c_str());
    else if (k == "--nulls")
      a.nulls = std::atoi(value().c_str());
    else if (k == "--forms")
      a.forms = split(value());
    else if (k == "--sizes")
      for (const auto& s : split(value())) a.sizes.push_back(std::atof(s.c_str()));
    else if (k == "--alpha")
      a.alpha = std::atof(value().c_str());
    else if (k == "--json")
      a.json = value();
    else if (k == "--verbose")
      a.verbose = true;
    else if (k == "--oracle-only")
      a.oracle_only = true;
    else if (k == "--reference-nulls")
      a.reference_nulls = true;
    else if (k == "--corner-hz")
      a.corner_hz = std::atof(value().c_str());
    else if (k == "--measurement-noise")
      a.measurement_noise = std::atof(value().c_str());
    else if (k == "--process-noise")
      a.process_noise = std::atof(value().c_str());
    else if (k == "--cutoff-hz")
      a.cutoff_hz = std::atof(value().c_str());
    else if (k == "--heldout-sigmas")
      a.heldout_sigmas = std::atof(value().c_str());
    else {
      std::fprintf(stderr,
                   "usage: bench_discrepancy_oracle [--records N] [--nulls M] [--forms a,b] [--sizes x,y]"
                   " [--alpha A] [--json FILE] [--verbose] [--oracle-only] [--corner-hz F]"
                   " [--measurement-noise K] [--process-noise K] [--cutoff-hz F] [--heldout-sigmas S]"
                   " [--reference-nulls]\n");
      std::exit(2);
    }
  }
  for (const auto& f : a.forms) {
    if (!gen::find_form(f)) {
      std::fprintf(stderr, "bench_discrepancy_oracle: unknown form %s\n", f.c_str());
      std::exit(2);
    }
  }
  if (a.forms.empty())
    for (const auto& f : gen::form_specs()) a.forms.push_back(f.name);
  return a;
}

/// The expression's form without its scanned number, spaces dropped and a product's factors
/// sorted: "deadzone(delta_f, 1.5)" -> "deadzone(delta_f,", "abs(p)*delta_f" = "delta_f*abs(p)".
std::string form_key(std::string text) {
  text.erase(std::remove(text.begin(), text.end(), ' '), text.end());
  const auto comma = text.find(',');
  if (comma != std::string::npos) return text.substr(0, comma + 1);
  std::vector<std::string> factors;
  int depth = 0;
  std::string cur;
  for (char c : text) {
    if (c == '(') ++depth;
    if (c == ')') --depth;
    if (c == '*' && depth == 0) {
      factors.push_back(cur);
      cur.clear();
    } else {
      cur += c;
    }
  }
  factors.push_back(cur);
  std::sort(factors.begin(), factors.end());
  std::string out;
  for (const auto& f : factors) out += (out.empty() ? "" : "*") + f;
  return out;
}

enum Kind { kRight, kOtherTerm, kLibrary, kAmbiguous, kUnexplained, kGust, kNone, kKinds };
const char* kind_name(int k) {
  static const char* names[] = {"right form",  "another term",    "library name", "ambiguous",
                                "unexplained", "side gust alone", "none"};
  return names[k];
}

/// The workflow's verdict on a record of `form` (empty: a null) against the oracle's equation and
/// text; `label` says what was named (terms as "L: p^3", library names by name).
Kind classify(const DiscrepancyResult& r, const std::string& form, const std::string& eq, const std::string& text,
              std::string& label) {
  label.clear();
  if (r.verdict == "none") return kNone;
  if (r.verdict == "ambiguous") {
    for (const auto& pair : r.ambiguous)
      for (const auto& n : pair) label += (label.empty() ? "" : " / ") + n;
    return kAmbiguous;
  }
  if (r.verdict == "unexplained") return kUnexplained;
  bool wrong = false, right = false, term = false;
  for (const NamedEffect& e : r.effects) {
    const std::string what = e.name == "term" ? e.equation + ": " + e.expression : e.name;
    label += (label.empty() ? "" : ", ") + what;
    if (e.name == "term") {
      term = true;
      if (e.equation == eq && form != "inflow_other_arm" && !form.empty() && form_key(e.expression) == form_key(text))
        right = true;
    } else if (e.name == "lateral_inflow" && form == "inflow_other_arm") {
      right = true;
    } else if (e.name != "lateral_gust") {
      wrong = true;
    }
  }
  if (wrong) return kLibrary;
  if (right) return kRight;
  if (term) return kOtherTerm;
  return kGust;
}

struct Cell {
  double size = 0.0;
  int records = 0, refused = 0, oracle = 0, oracle_cal = 0, oracle_iv = 0, untestable = 0, detected = 0;
  int kinds[kKinds] = {};
  std::map<std::string, int> other_terms, library;
  double seconds = 0.0;
};

/// Runs one record through the workflow with the oracle beside it; false if the oracle could not
/// be formed (the grammar lacks its operator).
DiscrepancyResult run_workflow(const FlightData& data, const gen::ModelSet& ms, const std::vector<Term>& oracle,
                               bool oracle_only, double& seconds, double cutoff_hz, double heldout_sigmas) {
  DiscrepancyOptions opt;
  if (heldout_sigmas >= 0.0) opt.heldout_sigmas = heldout_sigmas;
  if (cutoff_hz > 0.0) opt.processing.cutoff_hz = cutoff_hz;
  if (cutoff_hz < 0.0) opt.processing.filter_order = 0;  // diagnostic: no low-pass at all
  opt.test_terms = oracle;
  if (oracle_only) {
    opt.term_search = false;
    opt.candidates = {"constant_load"};
  }
  const auto t0 = std::chrono::steady_clock::now();
  DiscrepancyResult r = find_discrepancy(data, ms.model, ms.vehicle, opt);
  seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  return r;
}

/// A record that flies: the seed's, or the next try's when the loop diverged (counted).
gen::Record fly_record(const Args& args, const std::string& form, double size, std::uint64_t seed, int index,
                       int& refused, const gen::ModelSet*& ms, double& duration) {
  auto change = [&args](gen::Scenario& sc) {
    if (args.corner_hz > 0.0) {
      sc.sigma_L *= std::sqrt(args.corner_hz / sc.corner_L_hz);
      sc.sigma_Y *= std::sqrt(args.corner_hz / sc.corner_Y_hz);
      sc.corner_L_hz = sc.corner_Y_hz = args.corner_hz;
    }
    for (double* n : {&sc.noise_p, &sc.noise_v, &sc.noise_phi, &sc.noise_df, &sc.noise_u, &sc.noise_w})
      *n *= args.measurement_noise;
    sc.sigma_L *= args.process_noise;
    sc.sigma_Y *= args.process_noise;
  };
  for (int attempt = 0;; ++attempt) {
    const std::uint64_t s = seed + 1000000u * static_cast<std::uint64_t>(attempt);
    std::mt19937_64 rng(s * 31u + 7u);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    duration = 15.0 + 30.0 * u(rng);
    ms = &gen::model_set(1 + index % 5);
    gen::Record rec = gen::generate(form, size, s, duration, index % 2 == 1, ms->model, ms->vehicle, change);
    if (!rec.diverged) return rec;
    ++refused;
    std::printf("  refused: %s size %g seed %llu (set %d, %.1f s): the loop diverged\n",
                form.empty() ? "null" : form.c_str(), size, static_cast<unsigned long long>(s), 1 + index % 5,
                duration);
  }
}

/// The oracle's level calibrated on the nulls, per form: the p-value below which at most alpha of
/// the null records reject (0: no nulls, not calibrated).
using Calibration = std::map<std::string, double>;

Cell run_cell(const Args& args, const gen::FormSpec& form, std::size_t form_index, std::size_t size_index, double size,
              const Calibration& cal) {
  Cell c;
  c.size = size;
  for (int i = 0; i < args.records; ++i) {
    const std::uint64_t seed = 700000u + 10000u * form_index + 1000u * size_index + static_cast<std::uint64_t>(i);
    const gen::ModelSet* ms = nullptr;
    double duration = 0.0;
    const gen::Record rec = fly_record(args, form.name, size, seed, i, c.refused, ms, duration);
    const auto [eq, text] = gen::oracle_text(rec.hidden);
    std::vector<Term> oracle;
    try {
      oracle.push_back(gen::oracle_term(rec.hidden));
    } catch (const std::exception& e) {
      if (c.untestable == 0) std::printf("  oracle %s: %s not testable: %s\n", form.name, text.c_str(), e.what());
    }
    const DiscrepancyResult r =
        run_workflow(rec.data, *ms, oracle, args.oracle_only, c.seconds, args.cutoff_hz, args.heldout_sigmas);
    ++c.records;
    if (oracle.empty() || r.term_tests.empty() || !r.term_tests[0].note.empty()) ++c.untestable;
    const double p = r.term_tests.empty() ? 1.0 : r.term_tests[0].p_value;
    if (!r.term_tests.empty() && p <= args.alpha) ++c.oracle;
    if (!r.term_tests.empty() && cal.count(form.name) && p < cal.at(form.name)) ++c.oracle_cal;
    if (!r.term_tests.empty() && r.term_tests[0].iv_p_value <= args.alpha) ++c.oracle_iv;
    std::string label;
    const Kind k = classify(r, form.name, eq, text, label);
    ++c.kinds[k];
    if (k != kNone) ++c.detected;
    if (k == kOtherTerm) ++c.other_terms[label];
    if (k == kLibrary) ++c.library[label];
    if (args.verbose)
      std::printf("  %s size %g seed %llu set %d %.1f s: oracle %s p %.3g%s%s; %s%s%s (max |p| %.1f rad/s)\n",
                  form.name, size, static_cast<unsigned long long>(rec.scenario.seed), 1 + i % 5, duration,
                  text.c_str(), p, r.term_tests.empty() || r.term_tests[0].note.empty() ? "" : " ",
                  r.term_tests.empty() ? "" : r.term_tests[0].note.c_str(), kind_name(k), label.empty() ? "" : ": ",
                  label.c_str(), rec.max_p);
    if (args.verbose && (k == kNone || k == kOtherTerm)) {
      // Why the search did not name the form: the term trials of the form's equation that came
      // closest (the smallest p-values), with their reasons.
      std::vector<const CandidateTrial*> trials;
      for (const CandidateTrial& t : r.candidates)
        if (t.name == "term") trials.push_back(&t);
      std::sort(trials.begin(), trials.end(),
                [](const CandidateTrial* a, const CandidateTrial* b) { return a->p_value < b->p_value; });
      for (std::size_t j = 0; j < trials.size() && j < 3; ++j)
        std::printf("      %s %s: p %.3g, %s\n", trials[j]->equation.c_str(), trials[j]->expression.c_str(),
                    trials[j]->p_value, trials[j]->reason.substr(0, 400).c_str());
    }
  }
  return c;
}

std::string percent(int k, int n) {
  char buf[64];
  const Proportion p = wilson(k, n);
  std::snprintf(buf, sizeof buf, "%3d %3.0f%% [%3.0f,%3.0f]", k, n ? 100.0 * k / n : 0.0, 100.0 * p.lo, 100.0 * p.hi);
  return buf;
}

std::string listing(const std::map<std::string, int>& m) {
  std::string s;
  for (const auto& [k, n] : m) s += (s.empty() ? "" : "; ") + k + " x" + std::to_string(n);
  return s;
}

void print_form(const gen::FormSpec& form, const std::vector<Cell>& cells, double alpha, bool has_calibration) {
  std::printf("\n%s (oracle %s: %s)\n", form.name, form.equation, form.expression);
  std::printf("  %6s %4s %6s %6s %6s %6s %6s %6s %6s %6s %6s %6s %6s %6s %8s\n", "size", "n", "oracle", "or.cal",
              "or.iv", "detect", "right", "o.term", "lib", "ambig", "unexpl", "gust", "none", "refuse", "right/or");
  for (const Cell& c : cells) {
    std::printf("  %6g %4d %6d %6d %6d %6d %6d %6d %6d %6d %6d %6d %6d %6d %8s\n", c.size, c.records, c.oracle,
                c.oracle_cal, c.oracle_iv, c.detected, c.kinds[kRight], c.kinds[kOtherTerm], c.kinds[kLibrary],
                c.kinds[kAmbiguous], c.kinds[kUnexplained], c.kinds[kGust], c.kinds[kNone], c.refused,
                c.oracle ? (std::to_string(c.kinds[kRight]) + "/" + std::to_string(c.oracle)).c_str() : "-");
    if (c.untestable) std::printf("         the oracle could not be tested on %d records\n", c.untestable);
    if (!c.other_terms.empty()) std::printf("         another term: %s\n", listing(c.other_terms).c_str());
    if (!c.library.empty()) std::printf("         library name: %s\n", listing(c.library).c_str());
  }
  // The oracle's 90 %-power size and the right-form rate at and above it: at the nominal level
  // and, when the nulls calibrated it, at its measured level.
  for (const bool calibrated : {false, true}) {
    auto hits = [&](const Cell& c) { return calibrated ? c.oracle_cal : c.oracle; };
    const char* which = calibrated ? "calibrated oracle" : "oracle";
    const Cell* at90 = nullptr;
    int n = 0, right = 0;
    for (const Cell& c : cells) {
      if (!at90 && c.records > 0 && 10 * hits(c) >= 9 * c.records) at90 = &c;
      if (at90) {
        n += c.records;
        right += c.kinds[kRight];
      }
    }
    if (calibrated && !has_calibration) continue;
    if (!at90) {
      std::printf("  %s (alpha %g) under 90 %% power at every size of the grid\n", which, alpha);
      continue;
    }
    const Proportion o = wilson(hits(*at90), at90->records), r = wilson(right, n);
    std::printf(
        "  %s 90 %%-power size %g (%d of %d, 95 %% %.0f-%.0f %%); right form at sizes >= it: %d of %d "
        "(%.0f %%, 95 %% %.0f-%.0f %%; target >= 80 %%)\n",
        which, at90->size, hits(*at90), at90->records, 100 * o.lo, 100 * o.hi, right, n, n ? 100.0 * right / n : 0.0,
        100 * r.lo, 100 * r.hi);
  }
}

struct NullTally {
  int records = 0, refused = 0, alarms = 0;
  double seconds = 0.0;
  std::vector<std::string> alarm_lines;
  std::map<std::string, int> oracle_rejects, oracle_tested;  ///< per oracle form
  std::map<std::string, std::vector<double>> oracle_p;       ///< per oracle form, every null's p-value
  std::map<std::string, std::vector<double>> oracle_z;       ///< per oracle form, every null's coefficient / sigma
  std::map<std::string, std::vector<double>> iv_z;           ///< the same, instrumented by the excitation
  std::map<std::string, int> iv_rejects;
};

NullTally run_nulls(const Args& args) {
  NullTally t;
  for (int i = 0; i < args.nulls; ++i) {
    const gen::ModelSet* ms = nullptr;
    double duration = 0.0;
    gen::Record rec = fly_record(args, "", 0.0, 800000u + static_cast<std::uint64_t>(i), i, t.refused, ms, duration);
    if (args.reference_nulls) {
      test::GeneratorOptions o;
      o.seed = rec.scenario.seed;
      o.duration_s = duration;
      o.record_command = i % 2 == 1;
      rec.data = test::generate_flight(ms->model, ms->vehicle, test::HiddenEffects{}, o);
    }
    // Every oracle term on the null record, each with the magnitudes its form would have here.
    std::vector<Term> oracle;
    std::vector<std::string> names;
    for (const gen::FormSpec& f : gen::form_specs()) {
      gen::Hidden h = gen::draw_hidden(f.name, 1.0, rec.scenario.seed, ms->model, ms->vehicle);
      gen::resolve_references(h, rec.reference);
      try {
        oracle.push_back(gen::oracle_term(h));
        names.push_back(f.name);
      } catch (const std::exception&) {
      }
    }
    const DiscrepancyResult r =
        run_workflow(rec.data, *ms, oracle, args.oracle_only, t.seconds, args.cutoff_hz, args.heldout_sigmas);
    ++t.records;
    for (std::size_t k = 0; k < r.term_tests.size() && k < names.size(); ++k) {
      if (!r.term_tests[k].note.empty()) continue;
      ++t.oracle_tested[names[k]];
      t.oracle_p[names[k]].push_back(r.term_tests[k].p_value);
      if (r.term_tests[k].sigma > 0.0)
        t.oracle_z[names[k]].push_back(r.term_tests[k].coefficient / r.term_tests[k].sigma);
      if (r.term_tests[k].iv_sigma > 0.0)
        t.iv_z[names[k]].push_back(r.term_tests[k].iv_coefficient / r.term_tests[k].iv_sigma);
      if (r.term_tests[k].iv_p_value <= args.alpha) ++t.iv_rejects[names[k]];
      if (r.term_tests[k].p_value <= args.alpha) ++t.oracle_rejects[names[k]];
    }
    std::string label;
    const Kind k = classify(r, "", "", "", label);
    if (k != kNone) {
      ++t.alarms;
      char buf[512];
      std::snprintf(buf, sizeof buf,
                    "null seed %llu (set %d, %.1f s, disturbance corners L %.1f Hz, Y %.1f Hz): %s%s%s",
                    static_cast<unsigned long long>(rec.scenario.seed), 1 + i % 5, duration, rec.scenario.corner_L_hz,
                    rec.scenario.corner_Y_hz, r.verdict.c_str(), label.empty() ? "" : ": ", label.c_str());
      t.alarm_lines.push_back(buf);
    }
    if (args.verbose) std::printf("  null %d: %s %s\n", i, r.verdict.c_str(), label.c_str());
  }
  return t;
}

void print_nulls(const NullTally& t, double alpha) {
  std::printf("\nnull records: %d (refused %d)\n", t.records, t.refused);
  std::printf("  workflow alarms: %s\n", percent(t.alarms, t.records).c_str());
  for (const auto& line : t.alarm_lines) std::printf("    %s\n", line.c_str());
  std::printf("  oracle rejections at alpha %g, per oracle term:\n", alpha);
  for (const gen::FormSpec& f : gen::form_specs()) {
    const auto it = t.oracle_tested.find(f.name);
    if (it == t.oracle_tested.end()) {
      std::printf("    %-30s %s: %s  not tested\n", f.name, f.equation, f.expression);
      continue;
    }
    const int k = t.oracle_rejects.count(f.name) ? t.oracle_rejects.at(f.name) : 0;
    // Coefficient / sigma over the nulls: a mean away from 0 is a bias, a spread above 1 a
    // variance the test underestimates.
    double mean = 0.0, sd = 0.0;
    const std::vector<double>& z = t.oracle_z.count(f.name) ? t.oracle_z.at(f.name) : std::vector<double>{};
    for (double v : z) mean += v / static_cast<double>(std::max<std::size_t>(1, z.size()));
    for (double v : z) sd += (v - mean) * (v - mean) / static_cast<double>(std::max<std::size_t>(2, z.size()) - 1);
    std::printf("    %-30s %s: %-22s %s of %d; coefficient/sigma mean %+.2f sd %.2f\n", f.name, f.equation,
                f.expression, percent(k, it->second).c_str(), it->second, mean, std::sqrt(sd));
    double ivm = 0.0, ivsd = 0.0;
    const std::vector<double>& zi = t.iv_z.count(f.name) ? t.iv_z.at(f.name) : std::vector<double>{};
    for (double v : zi) ivm += v / static_cast<double>(std::max<std::size_t>(1, zi.size()));
    for (double v : zi) ivsd += (v - ivm) * (v - ivm) / static_cast<double>(std::max<std::size_t>(2, zi.size()) - 1);
    const int ki = t.iv_rejects.count(f.name) ? t.iv_rejects.at(f.name) : 0;
    std::printf("    %-30s    instrumented by the excitation %s; coefficient/sigma mean %+.2f sd %.2f\n", "",
                percent(ki, it->second).c_str(), ivm, std::sqrt(ivsd));
  }
}

/// Per form, the (floor(alpha n) + 1)-th smallest null p-value: rejecting below it, at most alpha n
/// of the nulls reject (the oracle at its measured level, column or.cal).
Calibration calibrate(const NullTally& t, double alpha) {
  Calibration cal;
  for (auto [name, ps] : t.oracle_p) {
    std::sort(ps.begin(), ps.end());
    const std::size_t k = static_cast<std::size_t>(std::floor(alpha * static_cast<double>(ps.size())));
    if (k < ps.size()) cal[name] = ps[k];
  }
  return cal;
}

void print_calibration(const Calibration& cal, double alpha) {
  if (cal.empty()) return;
  std::printf("  the oracle calibrated on these nulls (column or.cal): p below");
  for (const auto& [name, p] : cal) std::printf(" %s %.3g;", name.c_str(), p);
  std::printf(" (nominal %g)\n", alpha);
}

void write_json(const std::string& file, const Args& args, const std::map<std::string, std::vector<Cell>>& cells,
                const NullTally& nulls) {
  FILE* f = std::fopen(file.c_str(), "w");
  if (!f) {
    std::fprintf(stderr, "bench_discrepancy_oracle: cannot write %s\n", file.c_str());
    return;
  }
  std::fprintf(f, "{\"alpha\": %g, \"records\": %d, \"forms\": {", args.alpha, args.records);
  bool first_form = true;
  for (const auto& [name, list] : cells) {
    std::fprintf(f, "%s\n  \"%s\": [", first_form ? "" : ",", name.c_str());
    first_form = false;
    for (std::size_t i = 0; i < list.size(); ++i) {
      const Cell& c = list[i];
      std::fprintf(
          f,
          "%s\n    {\"size\": %g, \"records\": %d, \"refused\": %d, \"oracle\": %d, \"oracle_calibrated\": %d, "
          "\"detected\": %d",
          i ? "," : "", c.size, c.records, c.refused, c.oracle, c.oracle_cal, c.detected);
      const char* keys[] = {"right", "another_term", "library_name", "ambiguous", "unexplained", "gust", "none"};
      for (int k = 0; k < kKinds; ++k) std::fprintf(f, ", \"%s\": %d", keys[k], c.kinds[k]);
      std::fprintf(f, ", \"oracle_instrumented\": %d, \"seconds\": %.3f}", c.oracle_iv, c.seconds);
    }
    std::fprintf(f, "]");
  }
  std::fprintf(f, "},\n \"nulls\": {\"records\": %d, \"refused\": %d, \"alarms\": %d, \"oracle_rejections\": {",
               nulls.records, nulls.refused, nulls.alarms);
  bool first = true;
  for (const auto& [name, n] : nulls.oracle_tested) {
    const int k = nulls.oracle_rejects.count(name) ? nulls.oracle_rejects.at(name) : 0;
    std::fprintf(f, "%s\"%s\": [%d, %d]", first ? "" : ", ", name.c_str(), k, n);
    first = false;
  }
  std::fprintf(f, "}, \"instrumented_rejections\": {");
  first = true;
  for (const auto& [name, n] : nulls.oracle_tested) {
    const int k = nulls.iv_rejects.count(name) ? nulls.iv_rejects.at(name) : 0;
    std::fprintf(f, "%s\"%s\": [%d, %d]", first ? "" : ", ", name.c_str(), k, n);
    first = false;
  }
  std::fprintf(f, "}}}\n");
  std::fclose(f);
}

}  // namespace

int main(int argc, char** argv) {
  const Args args = parse_args(argc, argv);
  std::map<std::string, std::vector<Cell>> cells;
  double seconds = 0.0;
  int records = 0;
  const auto wall0 = std::chrono::steady_clock::now();
  // The nulls first: the oracle's null p-values calibrate its level for the forms' column or.cal.
  NullTally nulls;
  Calibration cal;
  if (args.nulls > 0) {
    nulls = run_nulls(args);
    print_nulls(nulls, args.alpha);
    cal = calibrate(nulls, args.alpha);
    print_calibration(cal, args.alpha);
  }
  seconds += nulls.seconds;
  records += nulls.records;
  for (std::size_t fi = 0; fi < gen::form_specs().size(); ++fi) {
    const gen::FormSpec& form = gen::form_specs()[fi];
    if (std::find(args.forms.begin(), args.forms.end(), form.name) == args.forms.end()) continue;
    const std::vector<double>& sizes = args.sizes.empty() ? form.sizes : args.sizes;
    for (std::size_t si = 0; si < sizes.size(); ++si) {
      cells[form.name].push_back(run_cell(args, form, fi, si, sizes[si], cal));
      seconds += cells[form.name].back().seconds;
      records += cells[form.name].back().records;
    }
    print_form(form, cells[form.name], args.alpha, !cal.empty());
    std::fflush(stdout);
  }
  const double wall = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  std::printf("\nworkflow time: %.1f s over %d records (%.3f s each); whole run %.1f s\n", seconds, records,
              records ? seconds / records : 0.0, wall);
  if (!args.json.empty()) write_json(args.json, args, cells, nulls);
  return 0;
}
