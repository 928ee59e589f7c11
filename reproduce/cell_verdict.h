#pragma once
/// The verdict of one cell of a reproduced table: the rules of `rig reproduce thesis`, apart from
/// the flights that feed them (reproduce/thesis_campaign.h).
///
/// Categories: each table has one, decided by the code from what its cells are computed from
/// (reproduce/campaign_spec.h, table_source()), never by the campaign file:
///  - flights: numbers whose character the plant file does not fix (ranges flown, fit metrics of
///    flights with the rig's sensing noise, estimator, vibration, gusts or effects). Verdicts by
///    equivalence (two one-sided tests on the mean's 95 % interval): `match` (the interval inside
///    the tolerance band), `differs` (wholly outside it, no reason or a reason whose check fails),
///    `explained` (wholly outside, with a reason whose check holds in this run) or `inconclusive`
///    (the interval across an edge of the band, with about how many seeds would decide it).
///  - calibrated: cells of a flights table the rig was tuned to; `match` or `differs`, never
///    explained.
///  - model: checks of the model, not of the vehicle. Arithmetic on a transcribed model file is
///    judged against the published number (a transcription check); the rig's re-identification of
///    its own plant file is judged against the plant file's exact value (a pipeline check:
///    TableSpec::reference_table), within half a unit of the published number's last digit (the
///    pipeline's error must not show in the number as the thesis prints it), on the mean of at
///    least kPipelineMinSeeds seeds, and printed beside the thesis's number. `match`, `differs` or
///    `inconclusive` (a pipeline check's interval across an edge).
///
/// Tolerance (never widened by the rig's noise): where the campaign file gives the thesis's
/// standard deviation of a cell, k of those (k the table's `thesis_sigmas`); else `relative`
/// times |published| (an eigenvalue's real part relative to the real part) or, per column, an
/// `absolute` one; never tighter than half a unit of the published number's last digit (its
/// rounding). A tolerance as wide as the value itself could not fail: such a cell is `not judged`,
/// with why. Each cell carries its tolerance's basis.
/// The rig's value is the mean over the seeds flown; its interval is the 95 % half-width of
/// that mean (Student t, n - 1 degrees of freedom), reported beside it. A table may ask for a
/// least number of seeds (`min_seeds`): with fewer, its flight cells are `inconclusive`.
///
/// A reason belongs to the cells it lists ("row / column", no wildcards) and carries the
/// predicate the command checks in the same run: the direction of the rig's value against the
/// published one (`rig: above | below`), a bound on the size of the difference (`max_off`, at
/// most kMaxOffPerGap times the cell's own gap: a wider one cannot fail) and the state sources
/// it applies to (`states`), all three required by the campaign file; and the cause, a second
/// flight with it added (`with`: scenario overrides) that must move the cell toward (or away
/// from) the published value by at least `at_least` of the gap. Direction, bound and states
/// describe a difference; without a cause flown in the run a reason explains nothing. A
/// predicate that does not hold makes the cell `differs`, and says which part failed.

#include <cmath>
#include <map>
#include <string>
#include <vector>

namespace nimble::reproduce {

/// What a table's cells are.
enum class Category { kFlights, kCalibrated, kModel };

/// "flights", "calibrated", "model".
const char* category_name(Category c);

/// A reason for cells outside the tolerance, with its predicate.
struct Reason {
  std::vector<std::string> cells;  ///< "row / column", each named explicitly
  std::string text;
  std::string rig;                          ///< "above" or "below": where the rig's value lies ("" unchecked)
  double max_off = -1.0;                    ///< bound on |rig - published| (< 0 unchecked)
  std::vector<std::string> states;          ///< state sources it holds for (empty unchecked)
  std::map<std::string, std::string> with;  ///< scenario overrides adding the cause (empty: none)
  std::string moves = "toward";             ///< with `with`: "toward" or "away" from the published value
  double at_least = 0.1;                    ///< with `with`: the least share of the gap it must move
};

/// A table of the campaign file.
struct TableSpec {
  std::string title;
  Category category = Category::kFlights;
  std::string why;  ///< what the cells are computed from, and so why the category (printed)
  /// A pipeline check: the table whose cells hold the plant file's exact values this one's are
  /// judged against (the rig's re-identification of its own plant); empty: judged against the
  /// published values.
  std::string reference_table;
  /// Cells of a flights table the rig was tuned to ("row / column"): judged as calibrated, with
  /// `calibrated_why`; the rest of the table is held out of the calibration.
  std::vector<std::string> calibrated_cells;
  std::string calibrated_why;
  double relative = 0.0;                       ///< tolerance relative to |published|
  std::map<std::string, double> absolute;      ///< by column
  double thesis_sigmas = 0.0;                  ///< k: tolerance k * thesis sigma where given
  std::map<std::string, double> thesis_sigma;  ///< "row / column" -> the thesis's sigma
  int min_seeds = 1;
  std::map<std::string, std::map<std::string, double>> published;  ///< row -> column -> value
  /// row -> column -> half a unit of the last digit as written in the campaign file ("0.900":
  /// 0.0005); a cell without it takes half_last_digit() of its value.
  std::map<std::string, std::map<std::string, double>> printed_half_digit;
  std::vector<std::string> row_order;
  std::map<std::string, std::vector<std::string>> column_order;  ///< row -> columns as written
  std::vector<Reason> reasons;
  /// The reason naming `cell` ("row / column"), or null.
  const Reason* reason_for(const std::string& cell) const;
};

/// The predicate of a reason as evaluated.
struct Check {
  std::string predicate;  ///< in words
  bool holds = false;
  std::string value;  ///< what was found
};

/// One judged cell.
struct Cell {
  std::string row, column;
  double published = 0.0;
  /// What the rig's value is judged against: the published value, or for a pipeline check
  /// (TableSpec::reference_table) the plant file's exact value.
  double reference = 0.0;
  double rig = 0.0;            ///< mean over the seeds
  std::vector<double> values;  ///< the rig's value on each seed flown, in the seeds' order
  double rig_sd = 0.0;         ///< seed-to-seed standard deviation (0 with one seed)
  double interval = 0.0;       ///< 95 % half-width of the mean (0 with one seed)
  int seeds = 0;
  double tolerance = 0.0;       ///< |rig - published| allowed for a match
  std::string tolerance_basis;  ///< "2 thesis sigma", "5 % of the value", "absolute"
  std::string category;
  std::string verdict;  ///< match, explained, differs, inconclusive, not judged
  std::string reason;   ///< the reason (explained) or why it differs / is not judged
  bool has_check = false;
  Check check;
  std::string repeats;      ///< "table / row / column" of an earlier cell with the same numbers
  int seeds_to_decide = 0;  ///< inconclusive: about how many seeds would decide it (0: none would)
};

/// What judge() needs beyond the numbers.
struct JudgeContext {
  std::string states;  ///< the run's state source
  /// The cell's values over the seeds on the flight with the reason's `with` (empty: not flown).
  std::vector<double> with_values;
  /// How a flight with the cause went wrong ("" if every one flew as its scenario asks): a cause
  /// that stops the flight (a failsafe, a diverged estimator) cannot explain a cell.
  std::string with_failure;
  /// A pipeline check's reference: the plant file's exact value of the cell (NaN: none).
  double reference = NAN;
};

/// Judges one cell (see the top of this header).
Cell judge(const TableSpec& table, const std::string& row, const std::string& column, const std::vector<double>& rig,
           const JudgeContext& context);

/// Half a unit of the last digit `value` is printed with (0.24: 0.005; 12.06: 0.005; 0.907:
/// 0.0005), the rounding every published number carries: the floor of every tolerance.
double half_last_digit(double value);

/// A pipeline check is judged on the mean of at least this many seeds: one seed has no interval.
inline constexpr int kPipelineMinSeeds = 2;

/// A reason's bound (`max_off`) may be at most this many times the cell's own gap: a wider bound
/// cannot fail, so it explains nothing.
inline constexpr double kMaxOffPerGap = 1.5;

/// The least number of seeds whose mean's 95 % half-width (Student t, seed-to-seed spread `sd`)
/// is below `distance` (the mean's distance to the nearer edge of the tolerance band); 0 when no
/// number does (the mean on the edge).
int seeds_to_decide(double sd, double distance);

/// Mean, standard deviation and 95 % half-width of the mean of `x`.
void mean_interval(const std::vector<double>& x, double* mean, double* sd, double* half_width);

}  // namespace nimble::reproduce
