#pragma once
/// The discrepancy workflow: given measured flight data and a lateral model, find where
/// they disagree, name the physical effect the model is missing, add it, and show the gap
/// shrink on data the fit did not see (rig discrepancy, ident/README.md "Discrepancy").
///
/// 0. Sensors. Every flight first goes through the data-compatibility stage
///    (discrepancy/data_compatibility.h): the gyro's scale factor, bias and time offset against the
///    attitude, from the kinematic relation phi_dot = p (+ the q, r terms), each tested at the
///    alarm rule's p_critical beyond a tolerance, named (sensor_scale, time_offset, sensor_bias,
///    with channel and interval) when its signature holds, and corrected in the record before
///    anything below sees it, so that a late gyro is not taken for an actuator delay nor a scale
///    error absorbed into the derivatives.
/// 1. Gap. The model's regression equations (thesis Eq 21, as rig identify):
///        L:  Ic/Izz p_dot  = Lp p + Lv v + sum_u L_u u
///        Y:  m v_dot_star  = Yp p + Yv v + sum_u Y_u u
///    and, when the data carries the flight board's command delta_f_cmd (a rig log does), the
///    flap actuator (thesis Eq 33):
///        F:  delta_f_dot   = F_f delta_f + F_cmd delta_f_cmd   (as given: -12.56, 8.97)
///    with the model's own derivatives (the model as given) and with its derivatives refit
///    (the baseline structure), on the measured states and inputs, low-passed as for
///    identification. Per output: RMSE, fit % (100 (1 - |e| / |y - mean y|)) and residual
///    whiteness, every figure on held-out data (below).
/// 2. Locate. Where the residual of the baseline structure lives, seen beside the linear
///    response to the excitation: each equation is refit with the excitation's filter bank
///    (DiscrepancyOptions::excitation, the exogenous phi_sp and delta_t through Laguerre filters)
///    so that the linear model's own error where the manoeuvre drives it (from noisy regressors,
///    the feedback, the zero-phase filter) is not taken for missing structure; what is left is
///    process and measurement noise, independent of the excitation, under a linear plant.
///    Two alarm tests per equation (L and Y; not the actuator's F, whose error on sampled data
///    follows the command's sampling and latency), each a test the candidates would pass too:
///      - frequency: the largest periodogram ordinate above the gust band, tested as sin and cos
///        at that frequency (Wald, batch means of the scores, Bonferroni over the band's
///        independent frequencies), which a resonance of the noise does not pass and a periodic
///        force does;
///      - state: z^2 and z^3 of each state and input's excitation part (its projection on the
///        bank), Bonferroni over the signals, confirmed above the gust band;
///    Frequency and state findings must also lower the held-out error (the candidates' held-out
///    rule). The energy shares of the manoeuvres, hovers and heaviest windows are reported as a
///    description, not a test: a closed-loop residual is larger where the manoeuvre is (on rig
///    flights the actuator equation's error follows the command's activity), so a window of more
///    energy is no evidence of a change; a change during the flight is tested by the candidates
///    effectiveness_step and effectiveness_drift, which hold the alarm rule.
/// 3. Name. A library of physically named candidate effects, each a set of regressor
///    columns in the L, Y (and F) equations (candidate_library()). Stepwise: in each round
///    every candidate not yet in the model is tried on the current model; it passes only if
///    all of
///      - significance: its Wald statistic with a covariance that allows coloured
///        residuals (batch means over blocks longer than the residual's correlation time)
///        reaches the partial-F rule F >= 20 (SIDPAC). The rule is applied as its
///        chi-square tail probability, P(chi2_1 >= 20) = 7.7e-6, so that it holds alike for
///        a group of k parameters, for the equations (Bonferroni) and for a candidate
///        scanned over M delays (Bonferroni over the M scan points). The Wald statistic's
///        tail is taken with the batch-means covariance's own scatter: from B blocks it is
///        Hotelling's T^2, W (B - k) / (k (B - 1)) ~ F(k, B - k), not chi2_k;
///      - the predicted squared error PSE = RSS / N + sigma_max^2 P / N falls in an
///        equation where it is significant (sigma_max^2 the variance of the dependent);
///      - for actuator_delay, the input acts mostly delayed: the delayed column's coefficient
///        is at least half of the input's total coefficient in that equation (delta_f in L
///        and Y, where the aerodynamics respond late to the measured flap output; the command
///        in F, where the actuator responds late to the command: the plant's actuator_delay);
///      - above the gust band: the same test on the equations high-passed at gust_band_hz
///        (y and every column) is significant at gust_band_alpha: an unmeasured side wind
///        drives v and correlates the error with v|v| in closed loop, but only at low
///        frequency;
///      - held-out: in K-fold cross-validation over contiguous blocks (the fit never sees
///        the block it predicts; a scanned candidate chooses its delay on the training
///        blocks only), the relative drop of the held-out squared error is larger than
///        its spread, one standard error (a Diebold-Mariano comparison: batch means of the
///        per-sample loss difference over blocks longer than its correlation time).
///    The passing candidate with the largest held-out drop enters, its terms only in the
///    equations where they are significant on their own; the search repeats on the new
///    residual. Two passing candidates whose regressors, with the model's
///    regressors projected out, correlate by more than 0.9 explain the same thing: the
///    verdict is `ambiguous` and names both.
///    flapping_forcing lies above the identification low-pass: after the stepwise search the
///    model as it stands is refit on the same data low-passed at flapping_cutoff_hz, and
///    sin/cos of the first two harmonics of a frequency scanned over flapping_band_hz are tried
///    with the same significance (Bonferroni over the band's independent frequencies, one per
///    1 / record length), PSE and held-out rules (each block's frequency found without it).
/// 4. Add. The baseline derivatives are refit together with the named effects.
/// 5. Gap after: the held-out table again, with the effects, and the gap in the band where each
///    effect's evidence lives (gap_bands: the band holding 90 % of its fitted contribution, in the
///    equations it entered; the harmonics of the flapping forcing on the wideband data; the side
///    wind's band below gust_band_hz), with a note where it cannot shrink (what the effect adds
///    beyond the model's own regressors is a small share of the error there). rig discrepancy also flies the
///    model as given and the augmented model in closed loop on the data's phi_sp
///    (validate_closed_loop, ident/closed_loop.h) and reports both (closed_loop).
///
/// effectiveness_drift ((t - t_mid) delta_f) and effectiveness_step (H(t - t*) delta_f, t*
/// scanned every 0.25 s from the end of the first cross-validation block to the start of the
/// last) change during the record: the step's significance counts Kish's effective blocks of
/// its coefficient's batch-means variance, its held-out prediction averages over t* by the
/// training blocks' profile likelihood, and it is named with t_change_s and an interval from
/// the profile of the residual sum of squares; the drift with its rate per minute of L_df and
/// a delta-method interval; both enter every equation they have a term in once significant in
/// one (ident/README.md "Effects that change during a flight").
///
/// lateral_gust has no regressor: a side wind v_g enters the side-force equation as -Yv v_g, a
/// random force with the wind's low-pass spectrum. After the search it is named from that
/// signature alone: the final Y residual's mean periodogram below gust_band_hz against its
/// level in a reference band above (an F test of the two bands' chi-square sums, with their
/// Satterthwaite degrees of freedom), at the partial-F rule's p_critical as every other
/// candidate. It leaves the held-out gap as it is.
///
/// Signatures (DiscrepancyOptions::signature_checks, on; docs/discrepancy.md "Effects outside the
/// library, and signatures"): a candidate that met every entry rule is named only if the rest of
/// its physical signature is in the data. Every effect: no generic term (the open world's
/// families) encompasses its terms in an equation where they are significant (alone it fits
/// better, beside them it is significant with Bonferroni over the terms tried, they add nothing
/// beside it; for actuator_delay against a lag the last is dropped), and a delay and a lag that
/// tie in every such equation give `ambiguous` with what would tell them apart. sensor_bias: the
/// same bias in the kinematic relation phi_dot = p, per held-out block b_k = (integral of p -
/// rise of phi) / duration, the blocks' mean against 0 by Student's t (K - 1 dof) at
/// gust_band_alpha; lateral_inflow: its roll moment is its side force at the arm, L_vv = arm Y_vv
/// (when both met the partial-F rule with one sign, only the assumed arm disagrees: the name is
/// kept with the measured arm and the assumption it contradicts, NamedEffect::contradicts).
/// A failed signature withdraws the name and reports the structure (Located::signature); it acts
/// only where a candidate met the alarm rule already, so the family-wise bound holds.
///
/// The open world (DiscrepancyOptions::term_search, on; "Terms" in docs/discrepancy.md): after
/// the library, generic terms of p, v and the inputs (powers and products to degree 3, x|x|,
/// one-sided, |p| and |v| times an input, the linear term of every recorded signal the
/// equations lack, an input's dead zone, backlash, saturation, rate limit and lag with a scanned
/// width, limit or time constant) are tried in L and Y with the entry rules, Bonferroni over
/// every family and equation, the coefficient's variance floored at the stationary residual's
/// (stationary_floor in discrepancy/discrepancy_parts.h), a confirmation through the excitation's
/// bank (a function of the excitation, which a linear plant's residual is independent of; not
/// for the linear forms, the lag and the rate limit, which it cannot see) and, for an input's
/// forms, most of the input acting through them. A found term is the effect `term`; a scanned
/// one carries its parameter with a 95 % profile interval (scan_interval).
///
/// Effects the model file already carries (section `effects:`, e.g. from an earlier run's
/// --model-out) belong to the baseline structure: refit with the derivatives, not tried again.
///
/// Verdicts: `effects` (one or more named), `ambiguous`, `unexplained` (nothing passed, but
/// a location test found structure: a periodic component or a nonlinear dependence on a state
/// or input), `none`.
///
/// One error rate for every alarm: a name, `ambiguous` and `unexplained` all come from tests at
/// the same p_critical (the partial-F rule's tail), each with its own Bonferroni factor, so the
/// chance of any alarm on a record where nothing is missing is at most the number of alarm
/// tests times p_critical (AlarmRule; about 1e-4 to 2e-4 per record). Measured over 240 null
/// records of varied length, noise, gains and model set: tests/ident/test_discrepancy_nulls.cc.

#include <cstddef>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "core/model.h"
#include "core/vehicle.h"
#include "discrepancy/data_compatibility.h"
#include "ident/flight_data.h"
#include "ident/identify.h"
#include "effects/effect.h"
#include "ident/signal.h"

namespace nimble::ident {

/// One regressor column of a candidate effect in one equation (effects/effect.h).
using CandidateTerm = effects::EffectColumn;

/// A physically named candidate effect: the definition of an effect of the rig's registry
/// (effects/registry.h).
using CandidateSpec = effects::EffectDefinition;

/// Every candidate effect, in a fixed order: the registry's effects' definitions.
const std::vector<CandidateSpec>& candidate_library();

/// Options of the workflow. Every threshold is documented where it is defined.
struct DiscrepancyOptions {
  ProcessingOptions processing;  ///< resampling and low-pass (defaults as rig identify: 512 Hz, 9 Hz)
  /// Candidates to try (names of candidate_library()); empty: every candidate the data supports.
  std::vector<std::string> candidates;
  /// Inputs of the baseline equations; empty: the model's inputs.
  std::vector<std::string> inputs;
  std::size_t folds = 10;       ///< K of the held-out cross-validation, >= 4
  double partial_f = 20.0;      ///< the partial-F rule (SIDPAC), applied as its chi2_1 tail
  double heldout_sigmas = 1.0;  ///< held-out drop must exceed this many standard errors (its spread)
  double collinearity = 0.9;    ///< |rho| above which two passing candidates are ambiguous
  std::size_t max_effects = 4;  ///< rounds of the stepwise search
  double delay_max_s = 0.060;   ///< actuator_delay scan: 1 sample .. this delay
  /// The flap actuator of the model as given, delta_f = gain / (s + pole) delta_f_cmd (thesis
  /// Eq 33; the plant's plant.flap): the actuator equation F of data that carries delta_f_cmd.
  double actuator_gain = 8.97;
  double actuator_pole_radps = 12.56;
  /// Known latency of the command path [s]: the actuator equation takes delta_f_cmd this much
  /// later (rounded to samples), and a named actuator_delay is the delay beyond it. The rig
  /// applies a command from an earlier controller tick: in lockstep one to two plant steps
  /// after the 512 Hz controller published it, in real time as much plus the LCM hop, so the
  /// default is one controller period (1/512 s, controller.rate_hz). Data from a flight board
  /// that logs its command when it is sent should set its own link's latency.
  double command_latency_s = 1.0 / 512.0;
  /// Confirmation band above side gusts [Hz]: a first-order Gauss-Markov wind with a
  /// correlation time of 0.5 s or longer (the plant's lateral_gust.tau_s) has 90 % of its
  /// variance below 2 Hz ((2/pi) atan(2 pi f tau)).
  double gust_band_hz = 2.0;
  double gust_band_alpha = 0.01;  ///< level of the confirmation above the gust band
  /// flapping_forcing: the band scanned [Hz] (the Nimble flaps at about 17 Hz; 10-25 Hz covers
  /// the throttle range) and the low-pass of the data it is tested on [Hz], above the second
  /// harmonic of the band's upper half (clamped to 0.4 x the rate).
  double flapping_band_hz[2] = {10.0, 25.0};
  double flapping_cutoff_hz = 60.0;
  /// The record's exogenous signals, which the location tests see the residual through
  /// (discrepancy_parts.h excitation_bank()): the roll set-point the controller tracks and the
  /// throttle the manoeuvre commands. Data from an open-loop flight should name its commanded
  /// input here (e.g. delta_f_cmd); with none of them in the data the location tests are not run.
  std::vector<std::string> excitation{"phi_sp", "delta_t"};
  double consistency_alpha = 0.01;  ///< level of the test that pooled flights agree on an effect
  double window_s = 1.0;            ///< time location windows [s]
  std::size_t whiteness_lags = 50;
  SegmentOptions segments;  ///< manoeuvre / hover segments of the time location
  /// Signature checks (docs/discrepancy.md "Effects outside the library, and signatures"): a
  /// candidate that meets every entry rule is named only if the rest of its physical signature is
  /// in the data (above). A failed signature withdraws the name and reports the structure
  /// (Located::signature). Measured: 2 of 120 out-of-library records get a library name (56.7 %
  /// without), the library's own naming as without (build/bin/bench_discrepancy_library).
  bool signature_checks = true;
  /// lateral_inflow's arm [m]: its roll moment is its side force at this arm, L_vv = arm Y_vv
  /// (the plant file's lateral_inflow, rig_configs/plant/nimble_plant.yaml: -2e-4 / -0.02).
  double inflow_arm_m = 0.01;
  /// How far the estimated L_vv / (arm Y_vv) may lie from 1 before the arm's test counts: a
  /// factor either way. An assumption: the vortex's centre of pressure is known to a factor of
  /// about 2 (the plant file's arm is a size, not a measurement), and closed-loop estimates of
  /// the two derivatives are biased by 30-40 % (measured on the 30 deg doublet with the inflow
  /// flown: Y_vv -0.0068 for -0.005).
  double inflow_arm_factor = 3.0;
  /// The open world (docs/discrepancy.md "Terms"): when no library effect earns its name, search
  /// generic terms (discrepancy/discrepancy_parts.h term_families) under the same entry rules and
  /// family-wise bound, up to term_rounds terms.
  bool term_search = true;
  std::size_t term_rounds = 2;
  /// Forms to test as given (`rig discrepancy --test-term "L: p^3"`), each once, on the model as
  /// given, beside the search: the test that knows the form, which no search over forms can beat
  /// (docs/discrepancy.md, "Power against the test that knows the form"). Its p-value is for the
  /// user to compare with their own level; it is not an alarm and changes no verdict
  /// (DiscrepancyResult::term_tests).
  std::vector<Term> test_terms;
  /// The data-compatibility stage, first on every flight (discrepancy/data_compatibility.h): the gyro's
  /// scale, bias and clock against the attitude from the kinematics, corrected before the search.
  CompatibilityOptions compatibility;
};

/// Statistics of one candidate tried in one round.
struct CandidateTrial {
  std::string name;  ///< a library effect, or "term" (the open-world search)
  /// "term": the equation and the expression tried (the scan's best point), and the passing
  /// forms that explain the same thing (|rho| above the collinearity bound) when it entered.
  std::string equation, expression;
  std::vector<std::string> alternatives;
  std::size_t round = 0;
  bool available = true;                    ///< false: the data lacks a channel it needs, or a regressor is not excited
  bool passed = false;                      ///< met every criterion in this round
  bool entered = false;                     ///< entered the model in this round
  std::string reason;                       ///< why it entered or not
  std::map<std::string, double> partial_f;  ///< per equation: Wald / k (coloured covariance)
  double p_value = 1.0;     ///< adjusted tail probability (equations and scan), compared with p_critical
  double p_critical = 0.0;  ///< P(chi2_1 >= partial_f option)
  std::size_t scan_points = 1;
  double delay_s = 0.0;                                 ///< chosen delay (actuator_delay)
  std::map<std::string, double> pse_before, pse_after;  ///< per equation
  double heldout_drop = 0.0;  ///< mean over folds of the relative drop of the held-out squared error
  double heldout_se = 0.0;    ///< its standard error over the folds
  std::map<std::string, double> parameters, sigma;  ///< the candidate's parameters (coloured sigma)
  /// actuator_delay, per equation: partial F of the part of delta_f that still acts
  /// instantaneously (reported; the criterion is the delayed fraction, parameter
  /// <eq>_df_fraction_delayed >= 0.5).
  std::map<std::string, double> instantaneous_f;
  /// Adjusted p-value of the same test on the equations high-passed above the gust band
  /// (1 for sensor_bias, which is exempt).
  double highpass_p = 0.0;
  /// The effect's signature beyond the equation it was found in (docs/discrepancy.md "Signature
  /// checks"): false when the candidate met every entry rule but its signature was absent, so it
  /// is not named and the structure it fitted is reported unexplained (Located::signature).
  bool signature_holds = true;
  /// The signature test's figures (sensor_bias: kinematic_bias_radps, its sigma_radps over the
  /// blocks, blocks, p_value).
  std::map<std::string, double> signature;
  std::string signature_note;   ///< what the signature predicted and what the data showed, when it failed
  std::string signature_rival;  ///< the generic terms its form was compared with, per equation
  /// A generic form this record cannot tell from the effect's (it fits as well alone, neither adds
  /// to the other): "term L: lag(delta_f, 0.0232)"; the verdict is then ambiguous. And what would
  /// tell them apart.
  std::string ambiguous_with, tell_apart;
  /// A signature that holds in form but contradicts a prior of the library's (lateral_inflow's
  /// arm): the measured value, its interval and the assumption, e.g. "arm 0.041 m [0.036,
  /// 0.046], outside the assumed 0.01 m x/ 3 (inflow_arm_m, inflow_arm_factor)".
  std::string contradicts;
};

/// A named effect with its parameters.
struct NamedEffect {
  std::string name;  ///< a library effect, or "term": a generic term the open-world search found
  /// Regression parameters, plus delay_s when scanned; effectiveness_drift: rate_per_min with
  /// rate_per_min_lo, _hi (95 %) and t_mid_s; effectiveness_step: t_change_s with
  /// t_change_lo_s, _hi_s (95 %) and fraction with fraction_lo, _hi.
  std::map<std::string, double> parameters;
  std::map<std::string, double> sigma;  ///< coloured-residual standard deviations
  /// "term": the equation it enters, its expression (core/term_expression.h), its coefficient
  /// [N m or N per unit of the expression] with the 95 % interval (coefficient +- 1.96 coloured
  /// sigma), the other forms that fit as well, and why each library effect was ruled out.
  std::string equation, expression;
  double coefficient = 0.0;
  double interval[2] = {0.0, 0.0};
  std::vector<std::string> alternatives;
  std::vector<std::pair<std::string, std::string>> ruled_out;  ///< (library effect, reason)
  std::string contradicts;  ///< the prior its measured value contradicts (CandidateTrial::contradicts)
  /// A sensor error of the compatibility stage (sensor_scale, time_offset, sensor_bias from the
  /// kinematics): the sensor's channel, the source it was compared with, the unit of its value
  /// (coefficient, with interval), and the flight it was found in. Empty for a model effect.
  std::string channel, against, unit, flight;
};

/// Held-out fit of one equation output.
struct OutputGap {
  std::string output;  ///< "p_dot" or "v_dot_star"
  std::string unit;
  double rmse_model = 0.0;   ///< the model as given (its own derivatives), whole record
  double rmse_before = 0.0;  ///< baseline structure refit, held-out
  double rmse_after = 0.0;   ///< with the named effects, held-out
  double fit_before_pct = 0.0, fit_after_pct = 0.0;
  bool white_before = false, white_after = false;
  bool white_tested = true;  ///< false: the record is too short for the whiteness lags (DiscrepancyResult::notes)
  double peak_psd_before = 0.0, peak_psd_after = 0.0;  ///< residual PSD at the located frequency (if any)
  /// The output [unit] and its held-out predictions before and after, on the grid t_s.
  Eigen::VectorXd measured, predicted_before, predicted_after;
};

/// The held-out gap in one frequency band of some equations: where an effect's evidence lives.
/// Like the scalar gap, the mean over `equations` of the held-out squared error in the band
/// divided by the dependent's sum of squares about its mean, so that a band's figures are its
/// share of the whole gap.
struct BandGap {
  std::string name;                    ///< "identification band", or the effect whose band it is
  std::vector<std::string> equations;  ///< e.g. {"L", "Y"}, {"F"}
  double lo_hz = 0.0, hi_hz = 0.0;
  double before = 0.0, after = 0.0;
  bool wideband = false;  ///< measured on the data low-passed at flapping_cutoff_hz, not the identification band
  /// Why the gap here cannot shrink by much, when it does not (the effect's fitted contribution
  /// is a small share of the held-out error in its band).
  std::string note;
};

/// A frequency where a residual has a significant peak.
struct FrequencyFinding {
  std::string output;
  double f_hz = 0.0;
  double ratio = 0.0;    ///< periodogram / local background
  double p_value = 1.0;  ///< Bonferroni-corrected over the bins scanned
};

/// A state or input whose nonlinear function (x^2, x^3 of its standardised value) the
/// residual depends on, with the model's regressors in the fit.
struct StateFinding {
  std::string output;
  std::string signal;
  double partial_r = 0.0;  ///< sqrt of the share of the residual sum of squares it explains
  double p_value = 1.0;    ///< Wald test, coloured covariance, Bonferroni over the signals tested
};

/// A time segment and its share of the residual energy.
struct TimeFinding {
  std::string output;
  std::string what;  ///< "manoeuvre", "hover" or "window"
  double start_s = 0.0, end_s = 0.0;
  double energy_share = 0.0;  ///< of the residual sum of squares
  double time_share = 0.0;    ///< of the record
};

/// Structure a candidate's terms fit (it met every entry rule) while the rest of its signature is
/// absent: it is not that effect, and no candidate explains it.
struct SignatureFinding {
  std::string candidate;               ///< e.g. "sensor_bias"
  std::vector<std::string> equations;  ///< where its terms were significant
  std::string note;                    ///< what the signature predicted and what the data showed
};

struct Located {
  std::vector<TimeFinding> time;
  std::vector<SignatureFinding> signature;
  std::vector<FrequencyFinding> frequency;
  std::vector<StateFinding> state;
  std::vector<std::string> excitation;  ///< the exogenous signals the tests saw the residual through
  std::string note;                     ///< why the tests did not run, when they did not
};

/// The one rule every alarm (a name, `ambiguous`, `unexplained`) is held to: each test (a
/// candidate in a round, the gust signature, each location test of each equation) alarms at
/// adjusted p <= p_critical, so the chance of any alarm on a record where nothing is missing
/// is at most tests * p_critical (Bonferroni), whatever the tests' dependence.
struct AlarmRule {
  double p_critical = 0.0;   ///< P(chi2_1 >= partial_f): the partial-F rule's tail
  std::size_t tests = 0;     ///< alarm tests this record ran
  double family_wise = 0.0;  ///< the bound tests * p_critical
};

/// One flight of a pooled analysis: its rows, noise level and its own estimate of each named
/// effect's parameters (the final model refit on its rows alone).
struct FlightEstimate {
  std::string source;
  std::size_t samples = 0;
  double start_s = 0.0, end_s = 0.0;                ///< its rows on the pool's time line
  std::map<std::string, double> noise;              ///< per equation: RMS of the baseline residual [scaled]
  std::map<std::string, double> parameters, sigma;  ///< the named effects' parameters
};

/// Whether a named effect is the same in all flights: Cochran's Q of the flights' estimates of
/// its parameters against their inverse-covariance weighted mean, chi2 with (flights - 1) k
/// degrees of freedom.
struct FlightConsistency {
  std::string effect;
  double q = 0.0, dof = 0.0, p_value = 1.0;
  bool same = true;     ///< p_value > consistency_alpha
  std::string differs;  ///< the flight whose estimate contributes most to Q, when not the same
};

/// Closed-loop comparison of one signal (rig validate --closed-loop): the model as given and
/// the augmented model, each flown by the controller copy on the data's phi_sp.
struct ClosedLoopGap {
  std::string output;  ///< "p", "v", "phi", "delta_f"
  double r2_before = 0.0, r2_after = 0.0;
  double rmse_before = 0.0, rmse_after = 0.0;
};

/// A form tested as given (DiscrepancyOptions::test_terms): its column beside the model's in its
/// equation, the coefficient with its coloured sigma (batch means, BatchRule), the Wald statistic
/// and its tail (Hotelling's, wald_tail) as one test: no scan, no Bonferroni.
struct TermTest {
  std::string equation, expression;
  double coefficient = 0.0, sigma = 0.0, wald = 0.0, p_value = 1.0;
  double blocks = 0.0;  ///< batches the covariance rests on
  /// The same form instrumented by the excitation (instrumented_wald): coefficient, sigma, p.
  double iv_coefficient = 0.0, iv_sigma = 0.0, iv_p_value = 1.0;
  std::string note;  ///< why it could not be tested (p_value 1), empty otherwise
};

/// Everything rig discrepancy reports.
struct DiscrepancyResult {
  std::string source;
  std::string model_name;
  std::string verdict;  ///< "effects", "none", "ambiguous" or "unexplained"
  std::string summary;  ///< one sentence saying what was found and where
  std::vector<NamedEffect> effects;
  std::vector<std::vector<std::string>> ambiguous;  ///< pairs of candidates that explain the same thing
  std::vector<CandidateTrial> candidates;           ///< every candidate tried, every round
  Located located;
  AlarmRule alarm_rule;
  std::vector<OutputGap> gap;
  /// The documented scalar of the gap: mean over the equations of the held-out squared
  /// error divided by the variance of the dependent (1 - R^2 on unseen data).
  double gap_before = 0.0, gap_after = 0.0;
  std::string gap_metric;
  /// The gap in the identification band and in the band (and equations) of each named effect.
  std::vector<BandGap> gap_bands;
  std::size_t folds = 0;
  double rate_hz = 0.0;
  double cutoff_hz = 0.0;  ///< identification low-pass of the data (0: none)
  std::size_t samples = 0;
  Eigen::VectorXd t_s;  ///< time grid of the gap table's series [s]
  /// Baseline refit and the refit with the named effects (all data), by parameter name.
  std::map<std::string, ParameterEstimate> baseline, augmented;
  /// The model with the refit derivatives and the named effects (DerivativeModel::effects).
  DerivativeModel augmented_model;
  /// Closed loop before (the model as given) and after (the augmented model), filled by the
  /// caller that has the controller (rig discrepancy) when the data has phi_sp; empty otherwise,
  /// with the reason in closed_loop_note (when flown, the note names the gain set).
  std::vector<ClosedLoopGap> closed_loop;
  std::string closed_loop_note;
  /// Pooled flights (find_discrepancy of several): each flight, and each named effect's
  /// consistency over them. Empty for one flight.
  std::vector<FlightEstimate> flights;
  std::vector<FlightConsistency> consistency;
  /// Diagnostics skipped because the record is too short for them, each saying how long a
  /// record it needs (the result stands without them).
  std::vector<std::string> notes;
  /// The data-compatibility stage of each flight (empty when it is off).
  std::vector<CompatibilityResult> compatibility;
  /// The forms tested as given (DiscrepancyOptions::test_terms), in their order.
  std::vector<TermTest> term_tests;
};

/// Runs the workflow on `data` against `model` (lateral3, inputs delta_f and optionally
/// delta_t, delta_d).
/// @throws DataError if the data lacks p, v, phi or an input of the model; std::invalid_argument
///         for an unknown candidate name, a non-lateral3 model or invalid options.
DiscrepancyResult find_discrepancy(const FlightData& data, const DerivativeModel& model, const Vehicle& vehicle,
                                   const DiscrepancyOptions& options);

/// The workflow on several flights of the same vehicle at once: each flight prepared on its own
/// and given its own held-out folds and its own noise level (its rows weighted by the pool's
/// residual level over its own), the evidence pooled, so an effect is named only when the pooled
/// test passes; then each flight's estimate of each named effect and whether they agree
/// (DiscrepancyResult::flights, consistency). The flapping forcing is not tried on a pool (its
/// phase is each flight's own): run it on each flight. With one flight, as find_discrepancy.
DiscrepancyResult find_discrepancy(const std::vector<FlightData>& flights, const DerivativeModel& model,
                                   const Vehicle& vehicle, const DiscrepancyOptions& options);

/// JSON report (keys verdict, effects, candidates, located, gap; see rig discrepancy --help).
std::string discrepancy_json(const DiscrepancyResult& result);

/// Plain-text report for the terminal.
std::string discrepancy_text(const DiscrepancyResult& result);

/// Writes a report an engineer can attach to a flight-test note into `dir` (created if
/// needed): report.md (verdict, named effects, gap table, every candidate, located findings)
/// and the PNGs it shows, drawn by gnuplot: outputs.png (each output with its held-out
/// predictions before and after), residuals.png and residual_psd.png (Welch PSDs of the
/// held-out residuals before and after, located frequencies marked in the text). Returns the
/// paths written. @throws std::runtime_error if gnuplot (gnuplot-nox) is missing or fails.
std::vector<std::string> write_discrepancy_report(const DiscrepancyResult& result, const std::string& dir);

}  // namespace nimble::ident
