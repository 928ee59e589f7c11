/// `rig model`: the linear model of a parameter set, its modes and eigenvectors.

#include <cmath>
#include <complex>
#include <cstdio>
#include <iostream>
#include <string>
#include <vector>

#include "cmdline/args.h"
#include "cli/commands.h"
#include "core/model.h"
#include "core/modes.h"
#include "core/vehicle.h"
#include "core/json_line.h"

namespace nimble::cli {
namespace {

/// For each published eigenvalue, the relative distance to the nearest computed one.
std::vector<double> published_errors(const std::vector<std::complex<double>>& published,
                                     const std::vector<std::complex<double>>& computed) {
  std::vector<double> errors;
  for (const auto& p : published) {
    double best = INFINITY;
    for (const auto& c : computed) best = std::min(best, std::abs(c - p));
    errors.push_back(best / std::max(std::abs(p), 1e-12));
  }
  return errors;
}

std::string format_complex(const std::complex<double>& z) {
  char buf[64];
  if (std::fabs(z.imag()) < 1e-12) {
    std::snprintf(buf, sizeof buf, "%.4f", z.real());
  } else {
    std::snprintf(buf, sizeof buf, "%.4f %c %.4fi", z.real(), z.imag() < 0 ? '-' : '+', std::fabs(z.imag()));
  }
  return buf;
}

/// Phase in degrees in (-180, 180], so that an opposite sign reads as 180 deg.
double phase_deg(const std::complex<double>& z) {
  const double deg = std::arg(z) * 180.0 / M_PI;
  return deg <= -180.0 + 1e-6 ? deg + 360.0 : deg;
}

void print_matrix(const char* name, const Eigen::MatrixXd& M, const std::vector<std::string>& rows,
                  const std::vector<std::string>& cols) {
  std::printf("%s\n%10s", name, "");
  for (const auto& c : cols) std::printf(" %13s", c.c_str());
  std::printf("\n");
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    std::printf("%10s", (rows[i] + "_dot").c_str());
    for (Eigen::Index j = 0; j < M.cols(); ++j) std::printf(" %13.6g", M(i, j));
    std::printf("\n");
  }
}

void print_text(const DerivativeModel& model, const Vehicle& vehicle, const StateSpace& ss,
                const std::vector<std::complex<double>>& eig, const std::vector<Mode>& modes) {
  std::printf("model    %s (%s)\n", model.name.c_str(), to_string(model.structure).c_str());
  std::printf("source   %s\n", model.source.c_str());
  std::printf("vehicle  %s: m = %.2f g, Ixx %.3g, Iyy %.3g, Izz %.3g, Ixz %.3g kg m^2\n", vehicle.name.c_str(),
              vehicle.mass_kg * 1e3, vehicle.Ixx_kgm2, vehicle.Iyy_kgm2, vehicle.Izz_kgm2, vehicle.Ixz_kgm2);
  std::printf("trim     u0 %.3g m/s, w0 %.3g m/s, theta0 %.3g rad, phi0 %.3g rad\n\n", model.trim.u0_mps,
              model.trim.w0_mps, model.trim.theta0_rad, model.trim.phi0_rad);

  std::vector<std::string> state_cols, input_cols;
  for (std::size_t i = 0; i < ss.states.size(); ++i) state_cols.push_back(ss.states[i] + "[" + ss.state_units[i] + "]");
  for (std::size_t i = 0; i < ss.inputs.size(); ++i) input_cols.push_back(ss.inputs[i] + "[" + ss.input_units[i] + "]");
  print_matrix("A", ss.A, ss.states, state_cols);
  std::printf("\n");
  print_matrix("B", ss.B, ss.states, input_cols);
  if (is_blackbox(model.structure)) {
    double kinematic = 0.0;
    plant_equivalent(model, vehicle, &kinematic);
    std::printf(
        "\nthe plant flies its p, r and v rows; its phi_dot row differs from the plant's kinematics "
        "(1 for p, tan(theta0) cos(phi0) for r, 0 else) by at most %.3g\n",
        kinematic);
  }

  std::printf("\neigenvalues [1/s]\n");
  for (const auto& z : eig) std::printf("  %s\n", format_complex(z).c_str());

  std::printf("\nmodes\n  %-3s %-22s %-12s %-9s %10s %7s %9s %14s\n", "#", "eigenvalue", "type", "stability",
              "wn[rad/s]", "zeta", "period[s]", "T2|T1/2[s]");
  for (std::size_t k = 0; k < modes.size(); ++k) {
    const Mode& m = modes[k];
    char t2[32];
    std::snprintf(t2, sizeof t2, "%s %.3f", m.stable ? "T1/2" : "T2", m.time_to_double_or_half_s);
    char period[16] = "-";
    if (m.oscillatory) std::snprintf(period, sizeof period, "%.3f", m.period_s);
    std::printf("  %-3zu %-22s %-12s %-9s %10.3f %7.3f %9s %14s\n", k + 1,
                (format_complex(m.eigenvalue) + (m.oscillatory ? " (pair)" : "")).c_str(),
                m.oscillatory ? "oscillatory" : "aperiodic", m.stable ? "stable" : "UNSTABLE",
                m.natural_frequency_radps, m.damping_ratio, period, t2);
  }

  std::printf(
      "\nnon-dimensional eigenvectors (rates / f, velocities / (2 Phi f r2), angles / 2pi;"
      " f = %.1f rad/s, Phi = %.3f rad, r2 = %.4g m), normalised on the attitude angle\n  %-8s",
      vehicle.flap_frequency_radps(), vehicle.flap_amplitude_rad, vehicle.r2_m, "state");
  for (std::size_t k = 0; k < modes.size(); ++k) std::printf(" %20s", ("mode " + std::to_string(k + 1)).c_str());
  std::printf("\n");
  for (std::size_t i = 0; i < ss.states.size(); ++i) {
    std::printf("  %-8s", (ss.states[i] + "+").c_str());
    for (const auto& m : modes) {
      char cell[48];
      std::snprintf(cell, sizeof cell, "%.3f (%.1f deg)", std::abs(m.eigenvector_nondim[i]),
                    phase_deg(m.eigenvector_nondim[i]));
      std::printf(" %20s", cell);
    }
    std::printf("\n");
  }

  if (!model.published_eigenvalues.empty()) {
    const auto errors = published_errors(model.published_eigenvalues, eig);
    std::printf("\npublished eigenvalues (%s)\n", model.source.c_str());
    double worst = 0.0;
    for (std::size_t i = 0; i < errors.size(); ++i) {
      std::printf("  %-22s nearest computed differs by %.2f %%\n",
                  format_complex(model.published_eigenvalues[i]).c_str(), 100.0 * errors[i]);
      worst = std::max(worst, errors[i]);
    }
    std::printf("  largest difference %.2f %%\n", 100.0 * worst);
  }
}

OrderedJson rows_json(const Eigen::MatrixXd& M) {
  OrderedJson rows = OrderedJson::array();
  for (Eigen::Index i = 0; i < M.rows(); ++i) {
    OrderedJson row = OrderedJson::array();
    for (Eigen::Index j = 0; j < M.cols(); ++j) row.push_back(M(i, j));
    rows.push_back(std::move(row));
  }
  return rows;
}

OrderedJson complex_list_json(const std::vector<std::complex<double>>& zs) {
  OrderedJson a = OrderedJson::array();
  for (const auto& z : zs) a.push_back(complex_json(z));
  return a;
}

OrderedJson mode_json(const Mode& m, const StateSpace& ss) {
  OrderedJson vector = OrderedJson::object();
  for (std::size_t i = 0; i < ss.states.size(); ++i) {
    vector[ss.states[i]] = {{"magnitude", std::abs(m.eigenvector_nondim[i])},
                            {"phase_deg", phase_deg(m.eigenvector_nondim[i])}};
  }
  return {{"eigenvalue", complex_json(m.eigenvalue)},
          {"oscillatory", m.oscillatory},
          {"stable", m.stable},
          {"natural_frequency_radps", m.natural_frequency_radps},
          {"damping_ratio", m.damping_ratio},
          {"period_s", m.period_s},
          {m.stable ? "time_to_half_s" : "time_to_double_s", m.time_to_double_or_half_s},
          {"eigenvector_nondim", std::move(vector)}};
}

std::string to_json(const DerivativeModel& model, const Vehicle& vehicle, const StateSpace& ss,
                    const std::vector<std::complex<double>>& eig, const std::vector<Mode>& modes) {
  OrderedJson j = {{"model", model.name},
                   {"model_file", model.file},
                   {"source", model.source},
                   {"structure", to_string(model.structure)},
                   {"vehicle", {{"name", vehicle.name}, {"file", vehicle.file}, {"mass_kg", vehicle.mass_kg}}},
                   {"trim",
                    {{"u0_mps", model.trim.u0_mps},
                     {"w0_mps", model.trim.w0_mps},
                     {"theta0_rad", model.trim.theta0_rad},
                     {"phi0_rad", model.trim.phi0_rad}}},
                   {"states", ss.states},
                   {"state_units", ss.state_units},
                   {"inputs", ss.inputs},
                   {"input_units", ss.input_units},
                   {"A", rows_json(ss.A)},
                   {"B", rows_json(ss.B)},
                   {"eigenvalues", complex_list_json(eig)}};
  j["modes"] = OrderedJson::array();
  for (const auto& m : modes) j["modes"].push_back(mode_json(m, ss));
  if (is_blackbox(model.structure)) {
    double kinematic = 0.0;
    plant_equivalent(model, vehicle, &kinematic);
    j["kinematic_row_difference"] = kinematic;
  }
  if (!model.published_eigenvalues.empty()) {
    const auto errors = published_errors(model.published_eigenvalues, eig);
    j["published"] = {{"eigenvalues", complex_list_json(model.published_eigenvalues)}, {"relative_errors", errors}};
  }
  return json_line(j);
}

}  // namespace

int run_model_command(const std::vector<std::string>& args) {
  std::string model_file, vehicle_file, json;
  cmdline::CommandLine cl("rig model",
                          "Builds A and B of the model's structure from its derivatives and vehicle, prints the\n"
                          "eigenvalues, the mode table and the non-dimensional eigenvectors.");
  cl->add_option("model", model_file, "the model file (rig_configs/models/*.yaml)")->required();
  cl->add_option("--vehicle", vehicle_file, "use this vehicle instead of the one the model file names")
      ->type_name("FILE");
  // This command's JSON goes to stdout when no file is named (`--json` alone, as it always has).
  cl.add_json(json, "the model (A, B, eigenvalues, modes)")->expected(0, 1);
  if (const auto done = cl.parse(args)) return *done;
  if (cl->count("--json") > 0 && json.empty()) json = "-";
  const DerivativeModel model = load_model(model_file);
  const Vehicle vehicle = load_vehicle(vehicle_file.empty() ? model.vehicle_file : vehicle_file);
  const StateSpace ss = build_state_space(model, vehicle);
  const auto eig = sorted_eigenvalues(ss.A);
  const auto modes = analyse_modes(ss, vehicle);
  if (json.empty()) {
    print_text(model, vehicle, ss, eig, modes);
  } else {
    cmdline::write_json(json, to_json(model, vehicle, ss, eig, modes));
  }
  return 0;
}

}  // namespace nimble::cli
