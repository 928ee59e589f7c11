#include "ident/model_writer.h"

#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <stdexcept>

#include "core/json_line.h"
#include "core/output_file.h"

namespace nimble::ident {
namespace {

std::string num(double x) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.9g", x);
  return buf;
}

/// Unit of a dimensional derivative, e.g. "Lp" -> "N m s/rad", "Y_df" -> "N per rad/s".
std::string derivative_unit(const std::string& name) {
  if (name.rfind("a_", 0) == 0 || name.rfind("b_", 0) == 0) {
    // A black-box entry a_<row>_<column> / b_<row>_<input>: the row's derivative per the column.
    const std::size_t split = name.find('_', 2);
    const std::string row = name.substr(2, split - 2), column = name.substr(split + 1);
    const auto rate_unit = [](const std::string& state) {
      return state == "v" ? std::string("m/s^2") : state == "phi" ? std::string("rad/s") : std::string("rad/s^2");
    };
    const auto state_unit = [](const std::string& state) {
      return state == "v" ? std::string("m/s") : state == "phi" ? std::string("rad") : std::string("rad/s");
    };
    if (name[0] == 'a') return rate_unit(row) + " per " + state_unit(column);
    const std::string input = column == "df" ? "rad/s" : column == "dt" ? "%" : "rad";
    return rate_unit(row) + " per " + input;
  }
  const char letter = name.empty() ? '?' : name[0];
  const bool moment = letter == 'L' || letter == 'N' || letter == 'M';
  const std::string force = moment ? "N m" : "N";
  const std::string rest = name.substr(1);
  if (rest == "p" || rest == "q" || rest == "r") return force + " s/rad";
  if (rest == "u" || rest == "v" || rest == "w") return force + " s/m";
  if (rest == "_df") return force + " per rad/s";
  if (rest == "_dt") return force + " per %";
  if (rest == "_dd" || rest == "_dw") return force + " per rad";
  return force;
}

}  // namespace

std::string format_model_yaml(const DerivativeModel& model, const std::string& vehicle_path,
                              const std::vector<std::string>& comments) {
  std::ostringstream out;
  for (const auto& c : comments) out << "# " << c << "\n";
  // Strings are written as JSON strings: valid YAML double-quoted scalars.
  out << "name: " << json_quote(model.name) << "\n";
  out << "source: " << json_quote(model.source) << "\n";
  out << "structure: " << to_string(model.structure) << "\n";
  if (model.structure == Structure::kLateral4) {
    out << "roll_yaw_coupling: " << (model.coupling == RollYawCoupling::kFull ? "full" : "decoupled") << "\n";
  }
  out << "vehicle: " << json_quote(vehicle_path) << "\n";
  out << "inputs: [";
  for (std::size_t i = 0; i < model.inputs.size(); ++i) out << (i ? ", " : "") << model.inputs[i];
  out << "]\n";
  out << "trim:\n";
  out << "  u0_mps: " << num(model.trim.u0_mps) << "\n";
  out << "  w0_mps: " << num(model.trim.w0_mps) << "\n";
  out << "  theta0_rad: " << num(model.trim.theta0_rad) << "\n";
  out << "  phi0_rad: " << num(model.trim.phi0_rad) << "\n";

  std::vector<std::string> names = stability_derivative_names(model.structure);
  for (const auto& in : model.inputs) {
    for (const auto& n : control_derivative_names(model.structure, in)) names.push_back(n);
  }
  out << "derivatives:\n";
  for (const auto& n : names) out << "  " << n << ": " << num(model.at(n)) << "   # " << derivative_unit(n) << "\n";

  if (!model.effects.empty()) {
    out << "# effects beyond the linear derivatives (rig discrepancy), parameters in SI units\n";
    out << "effects:\n";
    for (const auto& [name, params] : model.effects) {
      out << "  " << name << ":\n";
      for (const auto& [key, value] : params) out << "    " << key << ": " << num(value) << "\n";
    }
  }
  if (!model.terms.empty()) {
    out << "# generic terms (docs/models.md, \"Terms\"): coefficient * expression added to the equation's\n"
           "# force [N] or moment [N m]\n";
    out << "terms:\n";
    for (const auto& t : model.terms) {
      out << "  - {equation: " << t.equation << ", expression: \"" << t.expression.to_string()
          << "\", coefficient: " << num(t.coefficient) << "}\n";
    }
  }
  if (!model.published_eigenvalues.empty() || !model.published_sigma.empty()) {
    out << "published:\n";
    if (!model.published_eigenvalues.empty()) {
      out << "  # eigenvalues of A, [re, im] in 1/s\n  eigenvalues: [";
      for (std::size_t i = 0; i < model.published_eigenvalues.size(); ++i) {
        const auto& z = model.published_eigenvalues[i];
        out << (i ? ", " : "") << "[" << num(z.real()) << ", " << num(z.imag()) << "]";
      }
      out << "]\n";
    }
    if (!model.published_sigma.empty()) {
      out << "  # standard deviations of the derivatives\n  sigma:\n";
      for (const auto& n : names) {
        const auto it = model.published_sigma.find(n);
        if (it != model.published_sigma.end()) out << "    " << n << ": " << num(it->second) << "\n";
      }
    }
  }
  return out.str();
}

void write_model_yaml(const DerivativeModel& model, const std::string& file, const std::vector<std::string>& comments) {
  namespace fs = std::filesystem;
  const fs::path target = fs::absolute(file);
  const fs::path vehicle = fs::absolute(model.vehicle_file).lexically_normal();
  // Relative when the vehicle is near the model (e.g. ../vehicles/x.yaml), else absolute.
  const fs::path relative = vehicle.lexically_relative(target.parent_path().lexically_normal());
  int ups = 0;
  for (const auto& part : relative) ups += part == ".." ? 1 : 0;
  const std::string vehicle_path = (relative.empty() || ups > 2) ? vehicle.string() : relative.string();
  const std::string text = format_model_yaml(model, vehicle_path, comments);
  write_file(file, text);
}

}  // namespace nimble::ident
