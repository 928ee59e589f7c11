#pragma once
/// The parts of the discrepancy workflow (discrepancy/discrepancy.h), shared by the files that hold
/// them: the least squares from per-fold statistics and the tests on them
/// (discrepancy_stats.cc), the equations and the candidates' regressor columns
/// (discrepancy_columns.cc), the trials of the stepwise search (discrepancy_search.cc); the
/// location of what is left in the residual is declared in discrepancy_location.h
/// (discrepancy_locate.cc); discrepancy.cc joins them into find_discrepancy(). Not an
/// interface: nothing outside those files includes it.

#include <cstddef>
#include <iosfwd>
#include <map>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include <Eigen/Dense>

#include "core/terms.h"
#include "discrepancy/discrepancy.h"
#include "ident/spectrum.h"
#include "effects/registry.h"

namespace nimble::ident::discrepancy_parts {

using Eigen::Index;
using Eigen::MatrixXd;
using Eigen::VectorXd;
using Folds = std::vector<std::pair<Index, Index>>;

// ---------------------------------------------------------------------------------------
// Least squares from per-fold sufficient statistics.

struct Eq {
  std::string name;    // "L", "Y" or "F" (the flap actuator, when the data has its command)
  std::string output;  // "p_dot", "v_dot_star", "delta_f_dot"
  std::string unit;
  double scale = 1.0;
  VectorXd y;  // scale * dependent (times w)
  std::vector<std::string> names;
  std::vector<VectorXd> cols;  // times w
  /// Row weights when flights are pooled (each flight's rows 1 / its noise level, relative to
  /// the pool's); empty: none. y and cols carry them; augmented_design() applies them to added
  /// columns.
  VectorXd w;
};

/// A set of columns added to equation `eq`.
struct Addition {
  std::size_t eq = 0;
  std::vector<std::string> names;
  std::vector<VectorXd> cols;
};

MatrixXd design(const std::vector<VectorXd>& cols);

/// The columns of `eq` with `adds` (for this equation, weighted by eq.w) appended.
MatrixXd augmented_design(const Eq& eq, const std::vector<Addition>& adds);

struct FoldStats {
  std::vector<MatrixXd> G;  // C_k' C_k
  std::vector<VectorXd> b;  // C_k' y_k
  std::vector<double> s;    // y_k' y_k
  MatrixXd Gt;
  VectorXd bt;
  double st = 0.0;
};

/// How the coloured covariance batches a series: blocks of at least `min_block` samples and
/// longer than the residual's correlation (twice the lag at which its autocorrelation first
/// falls below 0.1), and at most n / 30, so that there are at least 30 blocks.
struct BatchRule {
  Index min_block = 1;

  /// Block length for the series e.
  Index block(const VectorXd& e) const {
    const Index n = e.size();
    const Index cap = std::max<Index>(1, n / 30);
    const VectorXd d = e.array() - e.mean();
    const double c0 = d.squaredNorm();
    Index lag = 1;
    if (c0 > 0.0) {
      for (; lag < cap; ++lag) {
        if (std::fabs(d.head(n - lag).dot(d.tail(n - lag)) / c0) < 0.1) break;
      }
    }
    return std::clamp<Index>(std::max<Index>(2 * lag, min_block), 1, cap);
  }
};

// ---------------------------------------------------------------------------------------
// The state of the stepwise search: the baseline equations plus what has entered.

struct Model {
  std::vector<Eq> eqs;
  std::vector<std::vector<Addition>> added;  // per equation, the additions that entered
  /// The effects that entered, in order: library names, and the terms the open-world search
  /// found as kTermPrefix + their parameter name ("term:L:p^3"), each also in found_terms.
  std::vector<std::string> effect_names;
  std::vector<Term> found_terms;

  MatrixXd X(std::size_t e) const { return augmented_design(eqs[e], added[e]); }
  std::vector<std::string> names(std::size_t e) const {
    std::vector<std::string> out = eqs[e].names;
    for (const auto& a : added[e]) out.insert(out.end(), a.names.begin(), a.names.end());
    return out;
  }
};

/// The fit of one equation with addition `a` appended (`with`: the fold stats of that
/// design): all its parameters and their coloured covariance, the addition's Wald statistic
/// and chi-square tail, and the equation's PSE before (`rss_before`) and after.
struct AdditionFit {
  VectorXd theta;
  MatrixXd cov;
  Index off = 0, k = 0;  ///< the addition's parameters: theta.segment(off, k)
  double wald = 0.0, p = 1.0;
  double blocks = 0.0;  ///< batches the covariance rests on (the tail's)
  double pse_before = 0.0, pse_after = 0.0;
};

/// lateral_gust from its signature (it has no deterministic regressor, so it is never tried in
/// the stepwise search). A side wind v_g enters the side-force equation as -Yv v_g: a
/// random force whose spectrum is that of the wind, low-pass (a first-order Gauss-Markov
/// wind: S(f) = A / (1 + (2 pi f tau)^2)). On the residual of the final model:
///   1. excess at low frequency: the mean periodogram of the Y residual below gust_band_hz
///      against its mean in the reference band from 1.5 gust_band_hz to f_ref_hi (the
///      equation noise's level, flat or rising with frequency for differentiated
///      measurements). For a flat background the ratio is F(2 K_lo, 2 K_ref) with K the
///      number of independent bins in each band (the padded bins count n / n_fft each), so
///      the test holds its level; a background rising with frequency makes it conservative.
///      Named only on the evidence every other candidate needs, p <= p_critical (the
///      partial-F rule's tail, 7.7e-6): the residual of a refit closed-loop record is not
///      stationary (manoeuvres come and go), its periodogram ordinates scatter more than
///      chi-square, and at location_alpha (0.01) 2 of 24 generator nulls measured p < 0.01.
///   2. parameters: tau_s and A from a Whittle fit of A / (1 + (2 pi f tau)^2) + N0 to the
///      periodogram, below f_ref_hi, of the Y residual of the model as given (N0 the
///      reference band's level; tau on a log grid 0.02-20 s); the force variance is
///      A / (4 tau) (one-sided PSD), and sigma_mps = sqrt(A / (4 tau)) / |Yv| with the model's
///      Yv. Rough: the model's own errors at low frequency add to it.
/// Sums of a periodogram's ordinates (and of their squares) in the gust band, (0, band_hz],
/// and in the reference band above it, [1.5 band_hz, ref_hi_hz]; bin counts of each.
struct GustBands {
  double lo = 0.0, ref = 0.0, lo2 = 0.0, ref2 = 0.0;
  Index k_lo = 0, k_ref = 0;
};

/// The flap actuator's equation (thesis Eq 33, delta_f_dot = -pole delta_f + gain
/// delta_f_cmd) joins the model as a third equation "F" when the data carries the flight
/// board's command delta_f_cmd and it moves: a delay before the actuator (the plant's
/// actuator_delay, a late link) shows there, where the L and Y equations, which see the
/// actuator's output, cannot see it. Always equation 2.
inline constexpr std::size_t kActuatorEq = 2;

// ---------------------------------------------------------------------------------------

/// effectiveness_step's grid of change times t* [s]: one every kChangeGridS, a quarter of a
/// second, the period of the slowest roll doublet of the identification trains (4 Hz): the
/// change shows only where delta_f moves, and a doublet is where it does.
inline constexpr double kChangeGridS = 0.25;

/// One scan point of a candidate (one, or one per delay of a scanned candidate): its columns,
/// the fold statistics of each equation it touches (indexed by equation) and the sum over the
/// equations of RSS after over RSS before.
struct ScanPoint {
  Index k = 0;  ///< the scan index (candidate_columns' `scan`)
  /// Per equation, the blocks the coloured covariance of the addition's coefficient rests on
  /// (effectiveness_step, ChangeProfile::kish); empty: every block of the record counts.
  std::vector<double> effective_blocks;
  /// A generic term: its variance floored at the stationary one (stationary_floor), computed
  /// where it can change the decision (the local test passes).
  bool stationary_floor = false;
  std::vector<Addition> adds;  ///< columns empty for effectiveness_step: Workflow::columns_of()
  std::vector<FoldStats> stats;
  std::vector<bool> touched;
  double rss_rel = 0.0;
};

/// effectiveness_step at its best t*, per equation (Workflow::change_profile): the scale of the
/// profile statistic over t*, 1 / (s2 kappa) (0 where the change does not enter), the effective
/// number of blocks of its coefficient's coloured variance, and the record's blocks.
///
/// The effective number is Kish's, (sum W_b)^2 / sum W_b^2 over the blocks (BatchRule) with W_b
/// the energy of the coefficient's influence (the row of (C'C)^-1 C') in block b: the
/// Satterthwaite degrees of freedom of the batch-means variance, a sum of the blocks' squared
/// scores whose variances go with W_b. The significance of the change takes its Hotelling tail
/// with it (wald_tail) instead of the record's blocks. The change column is zero before t*, so
/// at a t* near an end its coefficient rests on the few blocks of manoeuvres after (or before)
/// it, and the scan's maximum over t* goes where the variance estimate happens to be small:
/// counting every block took that estimate for far better known than it was (measured: null
/// records gave p 1.7e-10 at a t* 6 s before the end of a 52 s record, with 239 blocks counted
/// and 3.2 effective). wald_tail explains why the other candidates, whose columns span the
/// record, count every block.
struct ChangeProfile {
  std::vector<double> scale, kish, blocks;

  /// Leaves the scale only in the equations the change enters (all if it enters none).
  void restrict_to(const std::vector<bool>& use_eq);
  /// The fewest blocks of the equations with a scale (0 if none).
  double min_blocks() const;
};

/// An equation's model columns and dependent high-passed above the gust band.
struct HighPassed {
  MatrixXd X;
  VectorXd y;
};

/// The scan point's total relative RSS over the equations (those it does not touch count 1);
/// infinite when !ok or a fit is singular.
void close_scan_point(ScanPoint& pt, const std::vector<double>& rss_before, bool ok);

/// The scan point of the smallest total relative RSS (its rss_rel infinite: none can be fitted).
std::size_t best_scan_point(const std::vector<ScanPoint>& points);

/// Each equation's RSS of the fit on all folds (full_rss of each).
std::vector<double> full_rss_each(const std::vector<FoldStats>& stats);

/// Model::effect_names' prefix of a term found by the open-world search.
inline constexpr const char* kTermPrefix = "term:";
inline bool is_found_term(const std::string& effect_name) { return effect_name.rfind(kTermPrefix, 0) == 0; }

/// The open-world search's scanned families (dead zone and backlash widths, lag time constants):
/// points per scan, and the lag's time constants [s] (also the delay's lag signature).
inline constexpr std::size_t kTermScanPoints = 12;
inline constexpr double kLagGridS[2] = {0.004, 0.100};
/// The scanned families' parameters (TermFamily::parameter), reported with _lo and _hi.
inline constexpr const char* kScanParameters[] = {"w", "s", "r", "tau"};

/// One family of generic terms: one expression, or one per point of a scanned parameter.
struct TermFamily {
  std::string label;  ///< e.g. "p^3", "deadzone(delta_f, w)"
  std::vector<TermExpression> points;
  /// For a form an input acts through (its dead zone, backlash or lag): the input. The input
  /// must act mostly through it (Workflow::term_trial).
  std::string acts_through;
  /// A linear filter of a signal (the lag): no excitation confirmation, which cannot see a
  /// linear form (Workflow::term_trial).
  bool linear = false;
  /// A recorded signal's linear term (a missing derivative): confirmed by the test instrumented
  /// by the excitation (Workflow::instrument_confirms) instead of above the gust band, where a
  /// slow signal such as phi has little to show.
  bool instrumented = false;
  /// A scanned family: its parameter's name ("w", "s", "r", "tau"), the expression's text before
  /// the number ("ratelimit(delta_f, ") and the grid's values (points[i] has values[i]).
  std::string parameter, prefix;
  std::vector<double> values;
};

struct LocationFrame;

/// What the open-world search tests a term against in one equation: the location frame of the
/// current model and the record's excitation (LocationFrame; none without an exogenous signal),
/// and the record with each signal replaced by its excitation part (its projection on the
/// excitation's bank), one for every equation and round.
struct TermConfirmation {
  std::unique_ptr<LocationFrame> frame;
  const UniformData* excitation_parts = nullptr;
  /// The confirmations' Bonferroni factor: the families of the round that met the significance
  /// rule (0 before that is known: every family of the round).
  std::size_t bonferroni = 0;
};

/// The open world's families on `d` (discrepancy/discrepancy.h, "Terms"): for each of p, v and the
/// excited `inputs`: x^2, x^3, x*abs(x), and abs(x) (states) or pos(x) (inputs); the
/// products of two and three of them to degree 3; for each input its dead zone and backlash
/// (width scanned over 1-40 % of its largest magnitude) and first-order lag (4-100 ms).
std::vector<TermFamily> term_families(const UniformData& d, const std::vector<std::string>& inputs);

struct Workflow;

/// The profile interval of a scanned term's parameter (TermFamily::parameter) once the term won
/// its round: the equation's RSS over the family's grid and a grid 16 times finer between the
/// best point's neighbours; the statistic D(v) = (RSS(v) - RSS_min) / (s2 kappa), kappa the
/// ratio of the term's coloured to white variance (at least 1), is chi2_1 at the true value for a
/// regular parameter, so the 95 % interval is the set with D <= 3.84, reaching half a fine step
/// past its outermost points (to the next coarse point past a coarse one; an end of the grid: the
/// interval ends there). The term's expression
/// and column move to the fine grid's best; t.parameters gain the value and its _lo, _hi.
void scan_interval(const Workflow& wf, const Model& m, const TermFamily& fam, std::size_t eq, CandidateTrial& t,
                   Addition& add);

/// Each form of DiscrepancyOptions::test_terms tested once on `m` (the model as given), into
/// res.term_tests. @throws std::invalid_argument for an equation the record has not.
void test_given_terms(const Workflow& wf, const Model& m, DiscrepancyResult& res);

/// The open-world search, run when no library effect earned its name: each round tries every
/// family in the roll-moment and side-force equations without a term yet (one form per
/// equation: a later round looks for the effect in the other one) with the entry rules of a
/// library candidate, Bonferroni over the scan and over every family and equation; the passing
/// term with the largest held-out drop enters (its passing rivals that correlate above the collinearity
/// bound listed as its alternatives), up to DiscrepancyOptions::term_rounds. The trials that
/// passed, or the closest one when none did, go to res.candidates (name "term"); the terms that
/// entered join `m` (Model::effect_names, found_terms, added).
void term_search(const Workflow& wf, const std::vector<std::string>& inputs, Model& m, DiscrepancyResult& res);

struct Workflow {
  const DiscrepancyOptions& opt;
  const Vehicle& vehicle;
  const DerivativeModel& model;
  UniformData data;
  Folds folds;
  BatchRule batch;
  double p_critical = 0.0;
  /// Per equation, the stepwise model's columns high-passed (above_gust_band): the same for every
  /// candidate of a round, computed again when the model has gained columns. The model of the
  /// search only grows, so its number of columns names it.
  mutable std::map<std::size_t, HighPassed> high_passed;
  /// The open world's term columns on `data`, by expression (the same in every equation and
  /// round, and in the rival scans): term_column() once each.
  mutable std::map<std::string, VectorXd> term_columns;
  const VectorXd& term_column_of(const TermExpression& expr) const;

  /// Tries `spec` on model `m` in round `round`; fills the trial and, when it passes,
  /// the additions it would make.
  CandidateTrial trial(const CandidateSpec& spec, const Model& m, const std::vector<FoldStats>& base,
                       const std::vector<VectorXd>& base_cv, std::size_t round, std::vector<Addition>& best_adds) const;

  // The steps of trial() (discrepancy_search.cc).
  std::vector<ScanPoint> scan(const CandidateSpec& spec, const Model& m, const std::vector<Index>& delays,
                              const std::vector<double>& rss_before) const;
  double significance(const CandidateSpec& spec, const Model& m, const ScanPoint& P,
                      const std::vector<double>& rss_before, std::size_t scan_points, CandidateTrial& t,
                      std::vector<bool>& use_eq, std::string& p_eq) const;
  double above_gust_band(const Model& m, const ScanPoint& P, std::size_t scan_points) const;
  bool heldout(const CandidateSpec& spec, const Model& m, const std::vector<ScanPoint>& points, std::size_t best,
               const std::vector<FoldStats>& base, const std::vector<VectorXd>& base_cv,
               const std::vector<bool>& use_eq, const ChangeProfile& profile, CandidateTrial& t) const;
  void judge(CandidateTrial& t, const std::string& p_eq) const;
  /// The rest of a candidate's signature, once it met every entry rule (discrepancy_signatures.cc):
  /// lateral_inflow's arm, the kinematics that tell sensor_bias from constant_load, and every
  /// effect's form (rival_form_signature). A failed signature withdraws the pass and says why.
  void signature(const CandidateSpec& spec, const Model& m, const ScanPoint& P, CandidateTrial& t) const;
  /// sensor_bias's signature: the same bias in the kinematic relation of p and phi's derivative.
  /// Sets t.signature_holds and t.signature.
  void sensor_bias_signature(CandidateTrial& t) const;
  /// lateral_inflow's signature: its roll moment is its side force at the inflow's arm
  /// (DiscrepancyOptions::inflow_arm_m, inflow_arm_factor). Sets t.signature_holds, the note and
  /// t.signature (arm_z, arm_p, arm_ratio).
  void inflow_arm_signature(CandidateTrial& t) const;
  /// Every library effect's signature: its form is the data's, no generic term encompasses it
  /// (discrepancy_terms.cc). Sets t.signature_holds, t.signature_note, t.signature_rival and
  /// t.signature (rival_p_<eq>, own_p_<eq>).
  void rival_form_signature(const CandidateSpec& spec, const Model& m, const ScanPoint& P, CandidateTrial& t) const;
  /// One family of generic terms in equation `eq` (discrepancy_terms.cc), its p Bonferroni over
  /// the scan and `family_count`; fills the trial and, when it passes, its addition.
  /// A dead zone, backlash or lag of an input passes only if the input acts mostly through it.
  void acts_through(const TermFamily& fam, const Model& m, std::size_t eq, const ScanPoint& P, CandidateTrial& t) const;
  /// A recorded signal's linear term passes only if it is also significant with the excitation
  /// as instruments (the frame's excitation span), Bonferroni over `family_count`, at gust_band_alpha.
  void instrument_confirms(const TermExpression& expr, const Model& m, std::size_t eq, std::size_t family_count,
                           const TermConfirmation& confirm, CandidateTrial& t) const;
  /// A term passes only if it is also significant seen through the excitation (the location
  /// tests' frame), Bonferroni over `family_count`, at gust_band_alpha.
  void excitation_confirms(const TermExpression& expr, const std::string& eqname, std::size_t family_count,
                           const TermConfirmation& confirm, CandidateTrial& t) const;
  CandidateTrial term_trial(const TermFamily& fam, std::size_t eq, const Model& m, const std::vector<FoldStats>& base,
                            const std::vector<VectorXd>& base_cv, std::size_t round, std::size_t family_count,
                            const TermConfirmation& confirm, std::vector<Addition>& best_adds) const;

  // effectiveness_step (discrepancy_timevarying.cc).
  /// Every scan point of the change candidate `spec` on the grid (sample indices of t*): the fold
  /// statistics from those of the model (`base`) and prefix sums, without columns.
  std::vector<ScanPoint> scan_change(const CandidateSpec& spec, const Model& m, const std::vector<Index>& grid,
                                     const std::vector<FoldStats>& base, const std::vector<double>& rss_before) const;
  /// The columns of scan point `pt` (computed again when the scan kept none).
  std::vector<Addition> columns_of(const CandidateSpec& spec, const ScanPoint& pt) const;
  /// The profile at the best scan point `P` (ChangeProfile), in every equation it touches.
  ChangeProfile change_profile(const Model& m, const ScanPoint& P) const;
  /// The interval of the change time from the profile of the residual sum of squares over the
  /// scan: t_change_lo_s and t_change_hi_s in the trial's parameters.
  void change_interval(const Model& m, const std::vector<ScanPoint>& points, std::size_t best,
                       const ChangeProfile& profile, CandidateTrial& t) const;
  /// effectiveness_step's held-out predictions (`after`, per equation, each block predicted by the
  /// fit on the others): averaged over the change times, weighted by their profile likelihood on
  /// the training blocks. False if a cross-validation fit is singular.
  bool heldout_change(const CandidateSpec& spec, const Model& m, const std::vector<ScanPoint>& points,
                      const std::vector<bool>& use_eq, const ChangeProfile& profile,
                      std::vector<VectorXd>& after) const;
};

// --- discrepancy_timevarying.cc ---

/// effectiveness_step's scan grid: sample indices of t* every kChangeGridS from the end of the
/// first cross-validation block to the start of the last. The margin at each end is one block
/// (a tenth of the record with the default 10 folds): both sides of every t* then hold at least
/// a whole block, so that every training set of the held-out test sees the input before and after
/// the change, and a change within a block at the record's end, which only that block could
/// show, is not scanned.
std::vector<Index> change_grid(const UniformData& d, const Folds& folds);

/// The parameters a named time-varying effect reports beyond its coefficients, from the final fit
/// of `m` (delta method with the coloured covariance, 95 % intervals with Student t on the batch
/// means' blocks): effectiveness_drift, rate_per_min = 60 L_df_rate / L_df (the fraction of L_df
/// at t_mid per minute; from Y when only Y has the term) with rate_per_min_lo, _hi, and t_mid_s;
/// effectiveness_step, fraction = L_df_step / L_df (the change as a fraction of the value before
/// it) with fraction_lo, _hi, and t_change_s with its interval from the trial `t` that entered.
void time_varying_parameters(const Model& m, const BatchRule& batch, const UniformData& d, const CandidateTrial& t,
                             NamedEffect& eff);

// --- discrepancy_stats.cc ---

FoldStats fold_stats(const MatrixXd& C, const VectorXd& y, const Folds& folds);

/// fold_stats() of [X, c] from those of X (`base`, on the same y and folds): each fold's Gram
/// matrix bordered by X_k' c_k and c_k' c_k, in n q operations instead of n q^2 (the open world's
/// scans try a hundred columns on one model).
FoldStats fold_stats_with(const FoldStats& base, const MatrixXd& X, const VectorXd& y, const VectorXd& c,
                          const Folds& folds);

/// G x = B solved with column scaling (G scaled to unit diagonal, LDLT), for any number of
/// right-hand sides; `ok` false if G is (numerically) singular.
struct ScaledSolver {
  explicit ScaledSolver(const MatrixXd& G);
  MatrixXd solve(const MatrixXd& B) const { return scale.asDiagonal() * ldlt.solve(scale.asDiagonal() * B); }
  VectorXd scale;
  Eigen::LDLT<MatrixXd> ldlt;
  bool ok = false;
};

/// Solves G theta = b with column scaling; false if G is (numerically) singular.
bool solve(const MatrixXd& G, const VectorXd& b, VectorXd& theta);

/// RSS of the fit on all folds.
double full_rss(const FoldStats& f);

/// Covariance of the OLS estimate allowing coloured residuals: batch means of the scores
/// x_i e_i over blocks of `block` samples, Cov = G^-1 S G^-1 n / (n - q).
MatrixXd coloured_covariance(const MatrixXd& C, const VectorXd& e, Index block);

/// Number of blocks of length `block` in n samples.
double block_count(Index n, Index block);

/// Tail probability of a Wald statistic W of k parameters whose covariance is a batch-means
/// estimate from B blocks: the estimate has nu = B - 1 degrees of freedom, so W is
/// Hotelling's T^2 and W (nu - k + 1) / (k nu) ~ F(k, nu - k + 1). A chi-square reference
/// would ignore the estimate's own scatter, which matters far in the tail where the
/// partial-F rule sits. (Counting the blocks by the tested regressor's energy in them, Kish's
/// effective number, was measured too: it cut the power, lateral inflow 17 -> 15 of 24
/// generator records, forward-speed coupling on the rig's coupled doublet and a 6 ms delay on
/// the identification train no longer named, with 0 false names on 32-seed nulls either way
/// under process noise x5, measurement noise x4, other gains and 6-20 s records: the other
/// entry criteria carry the false-alarm control.)
double wald_tail(double wald, Index k, double blocks);

/// The part of x above f_hz: x minus its zero-phase Butterworth low-pass (order 4, applied
/// forward and backward), so that the two parts add up to x exactly.
VectorXd high_pass(const VectorXd& x, double f_hz, double rate_hz);

/// high_pass() of every column of A.
MatrixXd high_pass_columns(const MatrixXd& A, double f_hz, double rate_hz);

/// Per-fold stats of every equation of the current model.
std::vector<FoldStats> model_stats(const Model& m, const Folds& folds);

/// Fits `a` (see AdditionFit); false if the design is singular.
bool fit_addition(const Model& m, const Addition& a, const FoldStats& with, double rss_before, const BatchRule& batch,
                  AdditionFit& f);

/// Variance of coefficient j of the least-squares fit of y on C when its residual e is stationary:
/// e's autocovariance gamma_l over lags |l| <= bandwidth (Bartlett-tapered: a positive
/// semi-definite estimate), estimated from the whole record, applied to the coefficient's
/// influence w = C (C'C)^-1 e_j: sum over l of taper_l gamma_l sum_t w_t w_{t+l}, times n / (n - q).
/// Its precision rests on every block of the record, wherever the column has its energy.
double stationary_variance(const MatrixXd& C, const VectorXd& e, Index j, Index bandwidth);

/// A generic term's Wald test with its variance floored at the stationary one (the open world's
/// entry rule, docs/discrepancy.md "Terms"): the batch-means variance of a column whose energy
/// sits in a few blocks rests on those blocks alone and can be small by chance where the scan
/// over forms looks; under the null the equation error is process and measurement noise, whose
/// autocovariance the whole record estimates (stationary_variance, the batch rule's block as
/// bandwidth). The larger of the two is kept: the local one guards a residual larger where the
/// term lives. The tail counts the record's blocks, as every library candidate's does.
/// Single-column additions only (f.k == 1); f's cov, wald and p updated.
void stationary_floor(const Model& m, const Addition& a, const BatchRule& batch, AdditionFit& f);

/// Records the fit of `a` in the trial: partial F, parameters, sigma, PSE of its equation.
void record(const Model& m, const Addition& a, const AdditionFit& f, CandidateTrial& t);

/// RSS of the fit on every fold but k (on those folds).
double training_rss(const FoldStats& f, std::size_t k);

/// Relative drop of the held-out squared error and its standard error (a Diebold-Mariano
/// comparison of two predictors). Per sample, d_i = sum over equations of
/// (before_i^2 - after_i^2) / sum_j before_j^2; drop = sum_i d_i. Its standard error comes
/// from batch means of d over blocks longer than d's correlation time (block_length), so it
/// holds for coloured residuals; an effect that lives in a few manoeuvres is judged on all the
/// samples, not on the scatter of a few folds.
void heldout_drop(const std::vector<VectorXd>& before, const std::vector<VectorXd>& after, const BatchRule& batch,
                  double& drop, double& se);

/// Correlation of two columns after projecting out the columns of X.
double residual_correlation(const MatrixXd& X, const VectorXd& a, const VectorXd& b);

/// Held-out residual of y by the columns C (every fold predicted by the fit on the others).
VectorXd heldout_residual(const MatrixXd& C, const VectorXd& y, const Folds& folds);

/// Held-out residual of each equation (heldout_residual of its design).
std::vector<VectorXd> heldout_residuals(const Model& m, const Folds& folds);

/// The alarm rule's tail, P(chi2_1 >= options.partial_f), and the batch rule's smallest block
/// (four whiteness lag steps): the workflow's and the compatibility stage's, derived once.
double alarm_p_critical(const DiscrepancyOptions& options);
Index batch_min_block(const DiscrepancyOptions& options);

/// Full-data fit of the model: parameters with coloured sigma, and residuals.
std::map<std::string, ParameterEstimate> full_fit(const Model& m, const BatchRule& batch,
                                                  std::vector<VectorXd>* residuals);

// --- discrepancy_columns.cc ---

// ---------------------------------------------------------------------------------------
// The candidate library.

// The library is the registry's effects (effects/registry.h); the regressor columns of each are
// computed in candidate_columns().

/// A regressor column is excited when its standard deviation reaches this fraction of its
/// root mean square plus an absolute floor: a column that is (nearly) constant cannot be
/// told from the other regressors (except the intercept of sensor_bias, which is constant
/// by design). The floors are 10 resolution steps of the rig's actuator interface for the
/// inputs (the servos: kServoExcitationFloorRad, as rig identify uses) and 1e-9 otherwise.
double excitation_floor(const std::string& channel);

// ---------------------------------------------------------------------------------------
// Building the equations and candidate columns.

Folds make_folds(Index n, std::size_t k);

VectorXd delayed(const VectorXd& x, Index k);

/// The command as the actuator receives it: delta_f_cmd late by the command path's known
/// latency (DiscrepancyOptions::command_latency_s, rounded to samples), as signal
/// "delta_f_cmd_applied". The actuator equation and its delay candidate use it, so that a
/// named actuator_delay is the delay beyond that latency.
void add_applied_command(UniformData& d, double latency_s);

bool excited(const VectorXd& x, const std::string& channel);

bool has_actuator_equation(const UniformData& d);

/// The columns of candidate `spec` on the prepared data (`scan`: delay in samples for
/// actuator_delay, sample of the change for effectiveness_step: H(t - t*) is 1 from it on).
std::vector<Addition> candidate_columns(const CandidateSpec& spec, const UniformData& d, const Trim& trim, double g,
                                        Index scan);

/// The scan index of effect `name` with parameters `params` (a model's effects: section or a
/// trial's parameters) on `d`: the delay in samples of actuator_delay (delay_s, at least one
/// sample), the first sample at or after t_change_s of effectiveness_step, 0 otherwise.
Index scan_index(const CandidateSpec& spec, const std::map<std::string, double>& params, const UniformData& d);

/// t - t_mid of effectiveness_drift's column (t_mid the middle of the record) [s].
VectorXd drift_time(const UniformData& d);

/// sin and cos of h 2 pi f t, h = 1 .. harmonics, in every equation.
std::vector<Addition> harmonic_columns(const VectorXd& t_s, double f_hz, int harmonics, const Model& m);

/// Prediction of equation `eq` (scaled as eq.y) by the model as given: its own derivatives,
/// the values of the effects its file carries, and the actuator of the options.
VectorXd given_prediction(const Eq& eq, const DerivativeModel& model, const std::map<std::string, double>& known_values,
                          const DiscrepancyOptions& options);

/// The model's regression equations on `d`, with the columns of the effects the model file
/// carries (an earlier analysis named them): refit with the derivatives, not tried again.
/// Effects without a column on `d` (flapping forcing on low-passed data) are only listed.
Model build_baseline(const UniformData& d, const std::vector<Equation>& equations, const DerivativeModel& model,
                     const Vehicle& vehicle, const std::string& source, std::vector<std::string>* known,
                     std::map<std::string, double>* known_values);

/// The parameter of the input whose delay actuator_delay tests in equation `eq`: delta_f's
/// derivative in L and Y (L_df, Y_df), the command's gain in the actuator equation (F_cmd).
std::string delayed_input(const std::string& eq);

std::string fmt(double x, int digits = 3);

// --- discrepancy_search.cc ---

GustBands gust_bands(const Psd& P, double band_hz, double ref_hi_hz);

/// What the side gust's trial reads: the augmented fit's residuals and estimates, the Y columns
/// of every deterministic candidate the data supports (`extra`, fitted with the residual), and
/// the model as given: its side-force residual and Yv (where the whole wind force -Yv v_g shows).
struct GustEvidence {
  const std::vector<VectorXd>& resid;
  const std::map<std::string, ParameterEstimate>& fit;
  double rate_hz;
  double f_ref_hi;  ///< upper end of the reference band [Hz]
  std::vector<VectorXd> extra;
  VectorXd given_resid;
  double yv_given = 0.0;
};

CandidateTrial gust_trial(const CandidateSpec& spec, const Model& m, const GustEvidence& evidence,
                          const DiscrepancyOptions& opt, double p_critical);

/// Frequency in [lo, hi] where the residuals (each normalised by its variance) have the most
/// power at the frequency and its harmonics; samples where `mask` is false count as zero.
double scan_frequency(const std::vector<VectorXd>& resid, double rate, double lo, double hi, int harmonics,
                      const std::vector<bool>& mask);

/// The flapping_forcing candidate on wideband data (see the wideband stage of find_discrepancy);
/// its held-out residuals without and with the harmonics, when asked for.
CandidateTrial flapping_trial(const CandidateSpec& spec, const Model& m, const UniformData& d, const Folds& folds,
                              const DiscrepancyOptions& opt, double p_critical, const BatchRule& batch,
                              std::vector<VectorXd>* heldout_before = nullptr,
                              std::vector<VectorXd>* heldout_after = nullptr);

// --- discrepancy_bands.cc ---

/// A named effect's band gap is expected to shrink to at most this share of itself (by 20 %);
/// when it does not, the band's note says how much of the error there the effect can explain.
inline constexpr double kBandShrink = 0.8;
/// An effect's band holds this central share of its fitted contribution's energy.
inline constexpr double kEffectBandShare = 0.9;
/// Half width of a flapping harmonic's band [Hz] (at least 1.5 / T, the record's resolution).
inline constexpr double kFlappingBandHz = 0.25;

/// Sum of squares of x in [lo_hz, hi_hz] (its mean counts at 0 Hz), from its periodogram.
double band_energy(const VectorXd& x, double rate_hz, double lo_hz, double hi_hz);

/// The band holding the central `share` of x's energy over frequency (from the (1 - share) / 2
/// to the (1 + share) / 2 point of the cumulative), at least one resolution 1 / T wide.
std::pair<double, double> energy_band(const VectorXd& x, double rate_hz, double share);

/// The held-out gap of equations `eqs` of `m` in [lo_hz, hi_hz], before and after (held-out
/// residuals); given what the effect adds beyond the baseline's regressors per equation, a note
/// when the gap shrinks by less than 1 - kBandShrink saying what share of the error that is.
BandGap band_gap(const std::string& name, const Model& m, const std::vector<std::size_t>& eqs,
                 const std::vector<VectorXd>& before, const std::vector<VectorXd>& after, double rate_hz, double lo_hz,
                 double hi_hz, const std::vector<VectorXd>* contribution);

/// The gap table: each equation's held-out error before and after (cv_before, cv_after), the
/// model as given, whiteness, and the scalar gap with its metric.
void gap_table(const UniformData& d, const DerivativeModel& model, const DiscrepancyOptions& options,
               const std::map<std::string, double>& known_values, const Model& m,
               const std::vector<VectorXd>& cv_before, const std::vector<VectorXd>& cv_after, DiscrepancyResult& res);

/// The gap in the identification band, in the band of each named effect's fitted contribution
/// (kEffectBandShare of its energy, in the equations it entered), the side wind's band, and the
/// wideband stage's bands (`wide`).
void gap_bands(const UniformData& d, const DiscrepancyOptions& options, const Model& m,
               const std::vector<VectorXd>& cv_before, const std::vector<VectorXd>& cv_after, std::vector<BandGap> wide,
               DiscrepancyResult& res);

}  // namespace nimble::ident::discrepancy_parts
