#pragma once
/// Linear body-dynamics models of the Delfly Nimble built from identified
/// dimensional stability and control derivatives (thesis Appendix B).
///
/// Structures:
///  - lateral3:     x = [p v phi]        (thesis Eq 8.4 / paper Eq B.1)
///  - lateral4:     x = [p r v phi]      (thesis Eq B.16, or Eq 8.7 with decoupled L and N)
///  - longitudinal: x = [q u w theta]    (thesis Eq B.15 / E.11)
///  - blackbox3:    x = [p v phi]        (thesis Eq 8.6 / C.37: every entry of A and B free)
///  - blackbox4:    x = [p r v phi]      (thesis Eq 8.5 / C.30: every entry of A and B free)
/// Inputs are any of delta_f [rad/s] (flapping-frequency difference),
/// delta_t [%] (throttle, deviation from trim), delta_d [rad] (dihedral),
/// delta_w [rad] (wing root), each in the order the model file lists them.

#include <complex>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include <Eigen/Dense>

#include "core/config.h"
#include "core/terms.h"
#include "core/vehicle.h"

namespace nimble {

enum class Structure { kLateral3, kLateral4, kLongitudinal, kBlackbox3, kBlackbox4 };

/// True for the black-box structures: their parameters are the entries of A and B themselves,
/// named a_<row>_<column> and b_<row>_<input suffix> by the states (a_p_v: the v column of the
/// p-dot row; b_v_df: the delta_f column of the v-dot row), in SI units of the state space.
bool is_blackbox(Structure s);
/// True if the structure has the yaw rate r (lateral4, blackbox4).
bool has_yaw_rate(Structure s);

/// How the roll and yaw moment equations are combined in the lateral4 structure.
enum class RollYawCoupling {
  kFull,       ///< pdot = (Izz L + Ixz N)/Ic, rdot = (Ixz L + Ixx N)/Ic   (Eq B.16)
  kDecoupled,  ///< pdot = Izz/Ic L, rdot = Ixx/Ic N                       (Eq 8.7, C.8)
};

std::string to_string(Structure s);
/// @throws std::invalid_argument for an unknown name.
Structure structure_from_string(const std::string& name);

/// State names of a structure, e.g. {"p", "v", "phi"}.
const std::vector<std::string>& state_names(Structure s);
/// Units of the states, same order.
const std::vector<std::string>& state_units(Structure s);
/// Names of the stability derivatives the structure needs, e.g. {"Lp","Lv","Yp","Yv"}; for a
/// black-box structure the entries of A, row by row (a_p_p, a_p_v, a_p_phi, a_v_p, ...).
std::vector<std::string> stability_derivative_names(Structure s);
/// Names of the control derivatives for `input`, e.g. delta_f -> {"L_df","Y_df"}; for a
/// black-box structure the entries of B's column, one per state (b_p_df, b_v_df, b_phi_df).
std::vector<std::string> control_derivative_names(Structure s, const std::string& input);
/// Inputs a model may use.
const std::vector<std::string>& known_inputs();
/// Unit of an input ("rad/s", "%", "rad").
std::string input_unit(const std::string& input);
/// The suffix of an input in parameter names ("delta_f" -> "df", as in L_df and b_p_df).
std::string input_suffix(const std::string& input);
/// A black-box entry's name: a_<row>_<column> of A, b_<row>_<input suffix> of B (is_blackbox()).
std::string blackbox_a_name(const std::string& row, const std::string& column);
std::string blackbox_b_name(const std::string& row, const std::string& input);

/// Trim (reference) condition the linear model is taken about.
struct Trim {
  double u0_mps = 0.0;
  double w0_mps = 0.0;
  double theta0_rad = 0.0;
  double phi0_rad = 0.0;
};

/// A parameter set: structure, inputs, dimensional derivatives and trim.
struct DerivativeModel {
  std::string name;
  std::string file;          ///< file it was loaded from
  std::string source;        ///< table of the thesis/paper the numbers come from
  std::string vehicle_file;  ///< resolved path of the vehicle it goes with
  Structure structure = Structure::kLateral3;
  RollYawCoupling coupling = RollYawCoupling::kFull;
  std::vector<std::string> inputs;
  /// Dimensional derivatives in SI units: L*, N*, M* in N m per unit of the
  /// state/input; Y*, X*, Z* in N per unit of the state/input.
  std::map<std::string, double> derivatives;
  Trim trim;
  /// Published eigenvalues to compare against (optional, from the source table).
  std::vector<std::complex<double>> published_eigenvalues;
  /// Published parameter standard deviations (optional).
  std::map<std::string, double> published_sigma;
  /// Effects beyond the linear derivatives that a discrepancy analysis named (optional
  /// section `effects:` of a model file, written by rig discrepancy --model-out): effect name
  /// -> parameter name -> value, in SI units. The names and parameters are the effects
  /// registry's (effects/registry.h), which the plant and the discrepancy workflow check them
  /// against (check_model_effects()) when they use the model.
  std::map<std::string, std::map<std::string, double>> effects;
  /// Generic terms (optional section `terms:`, core/terms.h): each adds coefficient * expression
  /// to the force or moment of its equation (model_term_equations()), in SI.
  std::vector<Term> terms;

  /// Value of a derivative; @throws std::out_of_range naming it if absent.
  double at(const std::string& name) const;
};

/// Equations a `terms:` entry of a model of structure `s` may name: L, Y (lateral3); L, N, Y
/// (lateral4); none for the longitudinal and black-box structures.
std::vector<std::string> model_term_equations(Structure s);

/// Continuous-time linear state-space model xdot = A x + B u.
struct StateSpace {
  Eigen::MatrixXd A;
  Eigen::MatrixXd B;
  std::vector<std::string> states;
  std::vector<std::string> state_units;
  std::vector<std::string> inputs;
  std::vector<std::string> input_units;
};

/// Reads a model from a mapping (the root of a model file). Relative vehicle
/// paths are resolved against the file's directory.
/// @throws ConfigError on a missing/unknown key or derivative, a non-numeric
///         value, an unknown structure or input.
DerivativeModel model_from_config(ConfigMap& map);

/// Loads and validates a model file (rig_configs/models/*.yaml).
DerivativeModel load_model(const std::string& file);

/// Builds A and B from the derivatives, the trim and the vehicle (thesis Eqs B.15, B.16).
StateSpace build_state_space(const DerivativeModel& model, const Vehicle& vehicle);

/// The lateral model the plant flies for a black-box model (blackbox3 -> lateral3, blackbox4 ->
/// lateral4 with decoupled L and N, Eq 8.7), equal to it in the plant's linearised equations
/// about the model's trim: the p, r and v rows become derivatives (L = Ic/Izz a_p_*, N = Ic/Ixx
/// a_r_*, Y = m (a_v_* less the plant's own w0 p - u0 r), and the phi column, which no derivative
/// has, a term on phi less the plant's own gravity for Y. The phi-dot row is not flown: the
/// plant's kinematics give phi-dot (1 for p, tan(theta0) cos(phi0) for r, 0 for the rest);
/// `kinematic_row_difference` (if given) receives the largest difference of the model's row from
/// those (0 for a model whose phi-dot row is the kinematic one). Any other model is returned as
/// it is.
DerivativeModel plant_equivalent(const DerivativeModel& model, const Vehicle& vehicle,
                                 double* kinematic_row_difference = nullptr);

/// How a unit force or moment in `equation` (L, N [N m]; Y [N]) enters the state derivative of a
/// lateral model, in the order of its states (the column of B a control derivative of 1 has):
/// lateral3 L -> (Izz/Ic, 0, 0), Y -> (0, 1/m, 0); lateral4 with its roll-yaw coupling.
/// @throws std::invalid_argument for the longitudinal structure or an equation it lacks.
Eigen::VectorXd term_state_gain(const DerivativeModel& model, const Vehicle& vehicle, const std::string& equation);

/// Exact zero-order-hold discretisation: x[k+1] = Ad x[k] + Bd u[k].
struct DiscreteStateSpace {
  Eigen::MatrixXd Ad;
  Eigen::MatrixXd Bd;
  double dt_s = 0.0;
};

/// Exact ZOH discretisation via the matrix exponential of [[A B];[0 0]] dt.
/// @throws std::invalid_argument if dt_s is not positive and finite.
DiscreteStateSpace discretize_zoh(const StateSpace& ss, double dt_s);

}  // namespace nimble
