/// `rig turbulence-response`: a rig flight in Dryden side gusts (rig_configs/hover_turbulence.yaml)
/// against the closed-loop linear model driven by the same gust spectrum
/// (turbulence/hover_gust_response.h): Welch PSDs of the true p, v, phi inside the confidence
/// band of the model's expected Welch estimate below f_max, and the variances within their
/// uncertainty. The scenario (with the --set overrides the flight used) gives the model, the
/// vehicle, the controller's gains and the plant's gust.

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "cli/report_files.h"
#include "controller/attitude_controller.h"
#include "controller/manoeuvre.h"
#include "core/json_line.h"
#include "core/model.h"
#include "core/vehicle.h"
#include "ident/plots.h"
#include "ident/rig_log.h"
#include "effects/lateral_gust.h"
#include "effects/registry.h"
#include "plant/plant_model.h"
#include "scenario/scenario.h"
#include "turbulence/hover_gust_response.h"
#include "plots/gnuplot.h"

namespace nimble::cli {
namespace {

namespace fs = std::filesystem;
using namespace nimble::turbulence;

constexpr const char* kDescription =
    "A rig flight in Dryden side gusts (e.g. rig_configs/hover_turbulence.yaml flown with rig run\n"
    "... --log F) against the closed-loop linear model (lateral3 model, flap actuator, PD roll\n"
    "controller with its low-pass, the plant's Dryden gust filter): Welch PSDs of the true p, v,\n"
    "phi inside the confidence band of the model's expected Welch estimate up to --f-max, and\n"
    "their variances within the uncertainty of the model's. The scenario (with the same --set\n"
    "overrides as the flight) gives model, vehicle, gains and gust.";

/// What the analysis needs from the scenario.
struct Setup {
  DerivativeModel model;
  Vehicle vehicle;
  HoverLoopParameters params;
  std::string gain_set;
  std::string controller_input;
  std::vector<std::string> other_effects;  ///< plant effects on besides the gust
};

Setup setup_from(const std::string& file, const std::vector<Override>& overrides) {
  const Scenario scenario = load_scenario(file, overrides);
  Setup s;
  ConfigMap plant_section = scenario.section("plant");
  const plant::PlantConfig plant = plant::plant_config_from(plant_section);
  const auto& gust = plant.effects.get<effects::LateralGustConfig>();
  if (!gust.enabled || gust.form != effects::GustForm::kDryden || !(gust.sigma_mps > 0.0)) {
    throw std::invalid_argument(file +
                                ": plant.effects.lateral_gust must be enabled with form dryden and "
                                "sigma_mps > 0 (it is " +
                                std::string(gust.enabled ? "enabled" : "disabled") + ", " +
                                effects::to_string(gust.form) + ", sigma " + fmt("%g", gust.sigma_mps) + " m/s)");
  }
  // Every other enabled plant effect (the linear hover loop leaves them out), from the registry.
  for (const effects::Effect* e : effects::plant_effects()) {
    if (!e->definition.stochastic() && e->plant.enabled(plant.effects)) s.other_effects.push_back(e->name());
  }

  s.model = load_model(scenario.model_file);
  s.vehicle = load_vehicle(scenario.vehicle_file.empty() ? s.model.vehicle_file : scenario.vehicle_file);
  if (!s.model.effects.empty()) s.other_effects.push_back("the model's effects: section");
  ConfigMap controller_section = scenario.section("controller");
  const ControllerConfig controller = controller_config_from(controller_section);
  s.gain_set = controller.default_gain_set;
  if (const std::string file = manoeuvre_file(scenario); !file.empty()) {
    const Manoeuvre m = load_manoeuvre(file);
    std::vector<std::string> sets = {m.gain_set};
    for (const auto& seg : m.segments) sets.push_back(seg.gain_set.empty() ? m.gain_set : seg.gain_set);
    for (const auto& g : sets) {
      if (g != s.gain_set) {
        throw std::invalid_argument(file + ": the manoeuvre flies gain set '" + g +
                                    "' and the controller's default is '" + s.gain_set +
                                    "': the comparison needs one gain set throughout");
      }
    }
  }
  const GainSet& gains = roll_gain_set(controller, s.gain_set);
  s.params.kp_per_rad = gains.kp_per_rad;
  s.params.kd_per_radps = gains.kd_per_radps;
  s.params.lowpass_cutoff_hz = controller.roll_lowpass_cutoff_hz;
  s.params.roll_cmd_to_delta_f_radps = controller.roll_cmd_to_delta_f_radps;
  s.params.flap_gain_per_s = plant.flap.delta_f_gain_radps;
  s.params.flap_pole_radps = plant.flap.pole_radps;
  s.params.gust_sigma_mps = gust.sigma_mps;
  s.params.gust_time_scale_s = gust.time_scale_s;
  s.controller_input = process_run_options(scenario).controller_input;
  return s;
}

/// The true p, v, phi of the log from `skip_s` on, on the TRUTH grid.
std::map<std::string, Eigen::VectorXd> truth_records(const std::string& log, double skip_s, double& dt_s) {
  const ident::RigLogData data = ident::read_rig_log(log, ident::StateSource::kTruth);
  const ident::FlightData& truth = data.truth.channels.empty() ? data.measured : data.truth;
  std::map<std::string, Eigen::VectorXd> out;
  const ident::Channel& ref = truth.at("p");
  if (ref.t_s.size() < 3) throw std::invalid_argument(log + ": too few TRUTH samples");
  std::vector<double> steps(ref.t_s.size() - 1);
  for (std::size_t i = 0; i + 1 < ref.t_s.size(); ++i) steps[i] = ref.t_s[i + 1] - ref.t_s[i];
  std::nth_element(steps.begin(), steps.begin() + static_cast<long>(steps.size() / 2), steps.end());
  dt_s = steps[steps.size() / 2];
  for (std::size_t i = 0; i + 1 < ref.t_s.size(); ++i) {
    const double step = ref.t_s[i + 1] - ref.t_s[i];
    if (std::fabs(step - dt_s) > 1e-3 * dt_s) {
      throw std::invalid_argument(log + ": TRUTH is not evenly sampled (step " + fmt("%.6g", step) +
                                  " s at t = " + fmt("%.6g", ref.t_s[i]) + " s against " + fmt("%.6g", dt_s) +
                                  " s); fly with --clock lockstep");
    }
  }
  const double t0 = ref.t_s.front() + skip_s;
  std::size_t first = 0;
  while (first < ref.t_s.size() && ref.t_s[first] < t0) ++first;
  for (const char* name : {"p", "v", "phi"}) {
    const ident::Channel& c = truth.at(name);
    if (c.values.size() != ref.values.size()) throw std::invalid_argument(log + ": TRUTH channels differ in length");
    const std::size_t n = c.values.size() - std::min(first, c.values.size());
    out[name] = Eigen::Map<const Eigen::VectorXd>(c.values.data() + first, static_cast<Eigen::Index>(n));
  }
  return out;
}

std::string report_text(const std::string& scenario, const std::string& log, const Setup& s,
                        const ResponseComparison& c, double skip_s) {
  std::ostringstream out;
  out << "rig turbulence-response: " << log << " (scenario " << scenario << ")\n";
  out << "Closed loop: " << s.model.name << ", gain set " << s.gain_set << " (Kp " << s.params.kp_per_rad
      << " /rad, Kd " << s.params.kd_per_radps << " s/rad), low-pass " << s.params.lowpass_cutoff_hz << " Hz, map "
      << s.params.roll_cmd_to_delta_f_radps << " rad/s, flap " << s.params.flap_gain_per_s << "/(s+"
      << s.params.flap_pole_radps << "); Dryden gust sigma " << s.params.gust_sigma_mps << " m/s, T "
      << s.params.gust_time_scale_s << " s\n";
  if (s.controller_input != "truth") {
    out << "note: the controller flew on the " << s.controller_input
        << "; the model's controller reads the true state (the estimator's noise and lag are not in it)\n";
  }
  for (const auto& e : s.other_effects) out << "note: plant effect " << e << " is on; the linear model leaves it out\n";
  out << "Flight: " << c.samples << " TRUTH samples at " << fmt("%.4g", 1.0 / c.dt_s) << " Hz after the first "
      << skip_s << " s; Welch " << c.segments << " Hann segments of " << c.segment_length << " ("
      << fmt("%.3g", c.segment_length * c.dt_s) << " s), " << fmt("%.1f", c.dof) << " degrees of freedom, "
      << fmt("%.0f", 100 * c.level) << " % band x[" << fmt("%.3f", c.band_lower) << ", " << fmt("%.3f", c.band_upper)
      << "]\n";
  out << "PSD: S(omega) two-sided in unit^2/(rad/s), sigma^2 = (1/pi) int_0^inf S d omega "
         "(turbulence/spectral_density.h)\n\n";
  out << "Spectra up to " << fmt("%g", c.f_max_hz)
      << " Hz, flight Welch against the model's expected Welch estimate:\n";
  out << "  output  bins  counted  outside  allowed  mean ratio        max |E/analytical - 1|  verdict\n";
  for (const auto& o : c.outputs) {
    out << "  " << o.name << std::string(8 - o.name.size(), ' ') << fmt("%4.0f", double(o.bins))
        << fmt("%9.0f", double(o.counted)) << fmt("%9.0f", double(o.outside)) << fmt("%9.0f", double(o.allowed)) << "  "
        << fmt("%.3f", o.mean_ratio) << " +- " << fmt("%.3f", o.mean_ratio_sigma) << "   "
        << fmt("%-24.3f", o.max_analytical_deviation) << (o.bins_agree && o.mean_agrees ? "agrees" : "DISAGREES")
        << "\n";
  }
  out << "\nVariances, flight (sample variance) against the model (Lyapunov) with the model's sampling spread:\n";
  for (const auto& o : c.outputs) {
    const double z = (o.flight_variance - o.model_variance) / o.flight_variance_sigma;
    out << "  " << o.name << std::string(5 - std::min<std::size_t>(5, o.name.size()), ' ') << " flight "
        << fmt("%.4e", o.flight_variance) << "  model " << fmt("%.4e", o.model_variance) << " +- "
        << fmt("%.2e", o.flight_variance_sigma) << " (" << o.unit << ")^2  (" << fmt("%+.2f", z) << " sigma)  "
        << (o.variance_agrees ? "agrees" : "DISAGREES") << "\n";
  }
  out << "\n"
      << (c.agrees() ? "AGREES" : "DISAGREES") << ": "
      << "bins outside the band within the binomial bound (every other bin, false alarm 1e-3), mean ratio within 3 "
         "sigma "
         "of 1, variances within 3 sigma\n";
  return out.str();
}

std::vector<double> vec(const Eigen::VectorXd& x) { return std::vector<double>(x.data(), x.data() + x.size()); }

std::string report_json(const std::string& scenario, const std::string& log, const Setup& s,
                        const ResponseComparison& c) {
  OrderedJson j;
  j["scenario"] = scenario;
  j["log"] = log;
  j["model"] = s.model.name;
  j["gain_set"] = s.gain_set;
  j["controller_input"] = s.controller_input;
  j["gust"] = {
      {"form", "dryden"}, {"sigma_mps", s.params.gust_sigma_mps}, {"time_scale_s", s.params.gust_time_scale_s}};
  j["dt_s"] = c.dt_s;
  j["samples"] = c.samples;
  j["segment_length"] = c.segment_length;
  j["segments"] = c.segments;
  j["dof"] = c.dof;
  j["level"] = c.level;
  j["f_max_hz"] = c.f_max_hz;
  j["agrees"] = c.agrees();
  OrderedJson& outputs = j["outputs"] = OrderedJson::object();
  for (const auto& o : c.outputs) {
    OrderedJson& out = outputs[o.name];
    out["unit"] = o.unit;
    out["bins"] = o.bins;
    out["counted"] = o.counted;
    out["outside"] = o.outside;
    out["allowed"] = o.allowed;
    out["mean_ratio"] = o.mean_ratio;
    out["mean_ratio_sigma"] = o.mean_ratio_sigma;
    out["max_analytical_deviation"] = o.max_analytical_deviation;
    out["flight_variance"] = o.flight_variance;
    out["model_variance"] = o.model_variance;
    out["flight_variance_sigma"] = o.flight_variance_sigma;
    out["bins_agree"] = o.bins_agree;
    out["mean_agrees"] = o.mean_agrees;
    out["variance_agrees"] = o.variance_agrees;
    out["omega_radps"] = vec(o.omega_radps);
    out["welch"] = vec(o.welch);
    out["expected"] = vec(o.expected);
    out["analytical"] = vec(o.analytical);
  }
  return json_line(j);
}

/// response_psd.png and response_ratio.png: three panels each (p, v, phi), log frequency axis.
std::vector<std::string> plot_response(const fs::path& dir, const ResponseComparison& c) {
  std::ostringstream data;
  data << "# omega_radps, then per output p, v, phi: welch expected lower upper analytical\n";
  const Eigen::Index n = c.outputs.front().omega_radps.size();
  for (Eigen::Index k = 0; k < n; ++k) {
    data << fmt("%.9g", c.outputs.front().omega_radps[k]);
    for (const auto& o : c.outputs) {
      for (const double x : {o.welch[k], o.expected[k], o.lower[k], o.upper[k], o.analytical[k]})
        data << " " << fmt("%.9g", x);
    }
    data << "\n";
  }
  const fs::path dat = dir / "response_psd.dat";
  write_file(dat, data.str());
  const double w_max = 2.0 * M_PI * c.f_max_hz;
  const double x_hi = std::min(c.outputs.front().omega_radps[n - 1], 2.0 * M_PI * 20.0);
  std::vector<std::string> pngs;
  for (const bool ratio : {false, true}) {
    const std::string name = ratio ? "response_ratio" : "response_psd";
    const fs::path png = dir / (name + ".png");
    std::ostringstream s;
    s << "set terminal pngcairo size 1100,1300 font 'sans,10'\nset termoption noenhanced\n";
    s << "set output " << gp_quote(png.string()) << "\n";
    s << "set multiplot layout 3,1 title "
      << gp_quote(std::string(ratio ? "Flight Welch PSD / model expectation"
                                    : "Hover in Dryden gusts: flight against the closed-loop model") +
                  " (" + fmt("%.0f", 100 * c.level) + " % band, " + fmt("%.1f", c.dof) + " dof; compared up to " +
                  fmt("%g", c.f_max_hz) + " Hz)")
      << "\n";
    s << "set logscale x\nset grid\nset key top right\nset xrange [" << fmt("%.6g", c.outputs.front().omega_radps[0])
      << ":" << fmt("%.6g", x_hi) << "]\n";
    s << "set arrow 1 from " << fmt("%.6g", w_max) << ", graph 0 to " << fmt("%.6g", w_max)
      << ", graph 1 nohead dt 3 lc rgb '#555555'\n";
    if (ratio) {
      s << "set logscale y\nset yrange [0.1:10]\n";
    } else {
      s << "set logscale y\nset format y '%.0e'\n";
    }
    for (std::size_t i = 0; i < c.outputs.size(); ++i) {
      const auto& o = c.outputs[i];
      const int base = 2 + static_cast<int>(i) * 5;  // welch column
      s << "set title " << gp_quote(o.name) << "\nset xlabel 'omega [rad/s]'\n";
      if (ratio) {
        s << "set ylabel 'flight / expected [-]'\n";
        s << "plot " << gp_quote(dat.string()) << " using 1:(" << c.band_lower << "):(" << c.band_upper
          << ") with filledcurves lc rgb '#cce0f5' title 'band', '' using 1:($" << base << "/$" << base + 1
          << ") with linespoints pt 7 ps 0.5 lc rgb '#d62728' title 'flight / model', 1 with lines lc rgb '#1f77b4' "
             "notitle\n";
      } else {
        s << "set ylabel " << gp_quote("(" + o.unit + ")^2/(rad/s)") << "\n";
        s << "plot " << gp_quote(dat.string()) << " using 1:" << base + 2 << ":" << base + 3
          << " with filledcurves lc rgb '#cce0f5' title 'band', '' using 1:" << base + 1
          << " with lines lw 2 lc rgb '#1f77b4' title 'model (expected Welch)', '' using 1:" << base + 4
          << " with lines dt 2 lc rgb '#2ca02c' title 'model (analytical)', '' using 1:" << base
          << " with linespoints pt 7 ps 0.5 lc rgb '#d62728' title 'flight (Welch)'\n";
      }
    }
    s << "unset multiplot\n";
    run_gnuplot(dir, name, s.str());
    pngs.push_back(png.string());
  }
  return pngs;
}

}  // namespace

int run_turbulence_response_command(const std::vector<std::string>& args) {
  std::string scenario, log, json, plots;
  std::vector<Override> overrides;
  double skip_s = 5.0;
  ResponseComparisonOptions options;
  options.welch_segment = 8192;
  options.f_max_hz = 10.0;
  cmdline::CommandLine cl("rig turbulence-response", kDescription);
  cl->footer("Exit code: 0 if every check agrees, 1 if one does not, 2 bad usage or input.");
  cl->add_option("scenario", scenario, "the scenario the flight was flown with")->required();
  cl->add_option("log", log, "the flight's LCM log")->required();
  cmdline::each_value(cl->add_option("--set", "scenario override, as for rig run (repeatable)")
                          ->type_name("KEY.PATH=VALUE")
                          ->allow_extra_args(false)
                          ->multi_option_policy(CLI::MultiOptionPolicy::TakeAll),
                      [&overrides](const std::string& v) { overrides.push_back(parse_override(v)); });
  cl->add_option("--skip", skip_s, "drop the first S seconds of the flight (start-up)")
      ->capture_default_str()
      ->check(cmdline::kFinite & CLI::NonNegativeNumber)
      ->type_name("S");
  cl->add_option("--f-max", options.f_max_hz,
                 "compare up to this frequency [Hz]: above the closed-loop roll mode (2.4 Hz) and the flap "
                 "actuator (2 Hz), below the 15 Hz low-pass and the flapping frequency; on the truth the model "
                 "holds to 20 Hz and beyond")
      ->capture_default_str()
      ->check(cmdline::kFinite & CLI::PositiveNumber)
      ->type_name("HZ");
  cl->add_option("--welch-segment", options.welch_segment,
                 "Welch segment [samples], a power of two >= 8 (8192: 8.2 s at 1 kHz)")
      ->capture_default_str()
      ->check(cmdline::kPowerOfTwo)
      ->type_name("M");
  cl.add_json(json, "the report");
  cl.add_plots(plots,
               "response_psd.png (flight Welch, model expectation and band, analytical PSD) and "
               "response_ratio.png (flight / model with the band)");
  if (const auto done = cl.parse(args)) return *done;
  if (!plots.empty()) plots::require_gnuplot();

  const Setup s = setup_from(scenario, overrides);
  double dt_s = 0.0;
  const auto records = truth_records(log, skip_s, dt_s);
  const LinearSystem loop = hover_gust_loop(s.model, s.vehicle, s.params);
  const ResponseComparison c = compare_hover_response(loop, records, dt_s, options);

  if (json != "-") std::cout << report_text(scenario, log, s, c, skip_s);
  if (!json.empty()) cmdline::write_json(json, report_json(scenario, log, s, c));
  if (!plots.empty()) {
    const fs::path dir(plots);
    fs::create_directories(dir);
    for (const auto& p : plot_response(dir, c)) {
      if (json != "-") std::cout << "plot " << p << "\n";
    }
  }
  return c.agrees() ? 0 : 1;
}

}  // namespace nimble::cli
