#include "turbulence/hover_gust_response.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>

#include "turbulence/discretisation.h"
#include "turbulence/dryden.h"
#include "turbulence/lyapunov.h"
#include "turbulence/spectral_density.h"
#include "turbulence/spectral_estimates.h"
#include "turbulence/uncertainty.h"

namespace nimble::turbulence {
namespace {

enum : Eigen::Index { kP = 0, kV, kPhi, kDf, kLp, kLpDot, kG1, kG2, kStates };

int input_index(const DerivativeModel& model, const std::string& name) {
  for (std::size_t i = 0; i < model.inputs.size(); ++i) {
    if (model.inputs[i] == name) return static_cast<int>(i);
  }
  return -1;
}

/// Correlation of the powers of Welch bins j apart for the Hann window (j = 1, 2; 0 beyond).
double hann_bin_correlation(std::size_t j) {
  if (j == 0) return 1.0;
  if (j == 1) return 4.0 / 9.0;
  if (j == 2) return 1.0 / 36.0;
  return 0.0;
}

}  // namespace

LinearSystem hover_gust_loop(const DerivativeModel& model, const Vehicle& vehicle, const HoverLoopParameters& c) {
  if (model.structure != Structure::kLateral3) {
    throw std::invalid_argument("hover_gust_loop: model '" + model.name + "' must be lateral3, is " +
                                to_string(model.structure));
  }
  const int i_df = input_index(model, "delta_f");
  if (i_df < 0) throw std::invalid_argument("hover_gust_loop: model '" + model.name + "' has no delta_f input");
  if (!(c.kp_per_rad >= 0.0 && c.kd_per_radps >= 0.0 && c.lowpass_cutoff_hz > 0.0 &&
        c.roll_cmd_to_delta_f_radps > 0.0 && c.flap_gain_per_s > 0.0 && c.flap_pole_radps > 0.0 &&
        c.gust_sigma_mps > 0.0 && c.gust_time_scale_s > 0.0)) {
    throw std::invalid_argument(
        "hover_gust_loop: gains must be >= 0, cut-off, map, actuator, sigma and time scale > 0");
  }
  const StateSpace ss = build_state_space(model, vehicle);
  const ShapingFilter gust = time_based_second_order(c.gust_sigma_mps, c.gust_time_scale_s);
  const double wc = 2.0 * M_PI * c.lowpass_cutoff_hz;

  LinearSystem s;
  s.A = Eigen::MatrixXd::Zero(kStates, kStates);
  s.B = Eigen::MatrixXd::Zero(kStates, 1);
  // Aircraft with the flap actuator's output and the gust on the v column.
  s.A.topLeftCorner(3, 3) = ss.A;
  s.A.block(0, kDf, 3, 1) = ss.B.col(i_df);
  const Eigen::VectorXd v_column = ss.A.col(1);
  s.A.block(0, kG1, 3, 2) = -v_column * gust.system.C;
  // Actuator driven by the roll command.
  s.A(kDf, kDf) = -c.flap_pole_radps;
  s.A(kDf, kLp) = c.flap_gain_per_s * c.roll_cmd_to_delta_f_radps;
  // Butterworth on the PD output e = -(Kp phi + Kd p).
  s.A(kLp, kLpDot) = 1.0;
  s.A(kLpDot, kLp) = -wc * wc;
  s.A(kLpDot, kLpDot) = -std::sqrt(2.0) * wc;
  s.A(kLpDot, kPhi) = -wc * wc * c.kp_per_rad;
  s.A(kLpDot, kP) = -wc * wc * c.kd_per_radps;
  // Gust filter.
  s.A.block(kG1, kG1, 2, 2) = gust.system.A;
  s.B.block(kG1, 0, 2, 1) = gust.system.B;

  s.C = Eigen::MatrixXd::Zero(5, kStates);
  s.C(0, kP) = 1.0;
  s.C(1, kV) = 1.0;
  s.C(2, kPhi) = 1.0;
  s.C.block(3, kG1, 1, 2) = gust.system.C;
  s.C(4, kDf) = 1.0;
  s.D = Eigen::MatrixXd::Zero(5, 1);
  s.states = {"p", "v", "phi", "delta_f", "lp", "lp_dot", "gust_1", "gust_2"};
  s.inputs = {"w"};
  s.outputs = {"p", "v", "phi", "v_g", "delta_f"};
  s.validate();
  return s;
}

bool ResponseComparison::agrees() const {
  if (outputs.empty()) return false;
  for (const auto& o : outputs) {
    if (!(o.bins_agree && o.mean_agrees && o.variance_agrees)) return false;
  }
  return true;
}

ResponseComparison compare_hover_response(const LinearSystem& loop,
                                          const std::map<std::string, Eigen::VectorXd>& records, double dt_s,
                                          const ResponseComparisonOptions& options) {
  if (!(dt_s > 0.0) || !std::isfinite(dt_s)) throw std::invalid_argument("compare_hover_response: dt must be > 0");
  if (!(options.level > 0.0 && options.level < 1.0) || !(options.false_alarm > 0.0 && options.false_alarm < 1.0)) {
    throw std::invalid_argument("compare_hover_response: level and false_alarm must lie in (0, 1)");
  }
  if (!(options.f_max_hz > 0.0) || options.f_max_hz >= 0.5 / dt_s) {
    throw std::invalid_argument("compare_hover_response: f_max must lie in (0, Nyquist)");
  }
  const std::vector<std::pair<std::string, std::string>> names = {{"p", "rad/s"}, {"v", "m/s"}, {"phi", "rad"}};
  std::size_t N = 0;
  for (const auto& [name, unit] : names) {
    const auto it = records.find(name);
    if (it == records.end()) throw std::invalid_argument("compare_hover_response: no record of " + name);
    if (N == 0) N = static_cast<std::size_t>(it->second.size());
    if (static_cast<std::size_t>(it->second.size()) != N) {
      throw std::invalid_argument("compare_hover_response: the records of p, v, phi differ in length");
    }
  }
  const std::size_t M = options.welch_segment > 0 ? options.welch_segment : default_welch_segment(N);
  if (N < 2 * M) {
    throw std::invalid_argument("compare_hover_response: " + std::to_string(N) +
                                " samples are too few for Welch "
                                "segments of " +
                                std::to_string(M) + " (need at least two)");
  }

  const Eigen::VectorXd unit = Eigen::VectorXd::Ones(1);
  const Eigen::MatrixXd P = stationary_covariance(loop, unit);
  const DiscreteModel d = discretise(loop, unit, dt_s);
  const Eigen::VectorXd variances = output_variances(loop, unit, P);
  const Eigen::VectorXd q = sample_variance_weights(N);

  ResponseComparison out;
  out.dt_s = dt_s;
  out.samples = N;
  out.f_max_hz = options.f_max_hz;
  out.level = options.level;
  for (const auto& [name, unit_name] : names) {
    const Eigen::VectorXd& x = records.at(name);
    const SpectralEstimate e = welch(x, dt_s, M);
    out.segment_length = e.segment_length;
    out.segments = e.segments;
    out.dof = e.dof;
    const ConfidenceBand band = psd_confidence_band(e.dof, options.level);
    out.band_lower = band.lower;
    out.band_upper = band.upper;

    const Eigen::Index row = index_of(loop.outputs, name);
    const Eigen::RowVectorXd c = loop.C.row(row);
    const Eigen::VectorXd R = sampled_autocovariance(d.Phi, P, c, N - 1, 1e-9);
    const Eigen::Index nb = e.psd.size();
    const Eigen::VectorXd expected_all = welch_expectation(R, dt_s, M, static_cast<std::size_t>(nb));

    OutputComparison o;
    o.name = name;
    o.unit = unit_name;
    o.omega_radps = e.omega_radps.tail(nb - 1);
    o.welch = e.psd.tail(nb - 1);
    o.expected = expected_all.tail(nb - 1);
    o.analytical = output_psd(loop, unit, o.omega_radps).col(row);
    o.lower = band.lower * o.expected;
    o.upper = band.upper * o.expected;

    const double omega_max = 2.0 * M_PI * options.f_max_hz;
    double ratio_sum = 0.0;
    // From bin 2: bin 1 of a Hann segment carries the removal of the record mean.
    for (Eigen::Index k = 1; k < o.omega_radps.size() && o.omega_radps[k] <= omega_max; ++k) {
      ++o.bins;
      ratio_sum += o.welch[k] / o.expected[k];
      o.max_analytical_deviation =
          std::max(o.max_analytical_deviation, std::fabs(o.expected[k] / o.analytical[k] - 1.0));
      if (k % 2 == 1) {
        ++o.counted;
        if (o.welch[k] < o.lower[k] || o.welch[k] > o.upper[k]) ++o.outside;
      }
    }
    if (o.bins == 0) throw std::invalid_argument("compare_hover_response: no Welch bin below f_max");
    o.allowed = binomial_upper_quantile(o.counted, 1.0 - options.level, 1.0 - options.false_alarm);
    o.mean_ratio = ratio_sum / static_cast<double>(o.bins);
    double correlation_sum = 0.0;
    for (std::size_t i = 0; i < o.bins; ++i) {
      for (std::size_t j = 0; j < o.bins; ++j) correlation_sum += hann_bin_correlation(i > j ? i - j : j - i);
    }
    o.mean_ratio_sigma = std::sqrt(2.0 / e.dof * correlation_sum) / static_cast<double>(o.bins);

    o.model_variance = variances[row];
    o.flight_variance = sample_variance(x);
    o.flight_variance_sigma = quadratic_estimate_std(q, R);
    o.bins_agree = o.outside <= o.allowed;
    o.mean_agrees = std::fabs(o.mean_ratio - 1.0) <= 3.0 * o.mean_ratio_sigma;
    o.variance_agrees = std::fabs(o.flight_variance - o.model_variance) <= 3.0 * o.flight_variance_sigma;
    out.outputs.push_back(std::move(o));
  }
  return out;
}

}  // namespace nimble::turbulence
