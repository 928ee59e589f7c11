#include "turbulence/ce500_config.h"

#include <cmath>
#include <stdexcept>

namespace nimble::turbulence {
namespace {

int line_of(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? -1 : mark.line + 1;
}

/// A finite number in a list item; errors name the item as key[i].
double list_number(const ConfigMap& map, const std::string& item_path, const YAML::Node& item) {
  if (!item.IsScalar()) throw ConfigError(map.file(), item_path, yaml_text(item), "must be a number", line_of(item));
  const std::string& text = item.Scalar();
  std::size_t used = 0;
  double x = 0.0;
  try {
    x = std::stod(text, &used);
  } catch (const std::exception&) {
    used = 0;
  }
  if (used == 0 || used != text.size() || !std::isfinite(x)) {
    throw ConfigError(map.file(), item_path, text, "must be a finite number", line_of(item));
  }
  return x;
}

/// A list of exactly `count` numbers (count 0: any non-empty length).
std::vector<double> number_list(ConfigMap& map, const std::string& key, std::size_t count) {
  const YAML::Node node = map.get_node(key);
  if (!node.IsSequence() || (count > 0 && node.size() != count) || node.size() == 0) {
    map.fail(key, count > 0 ? "must be a list of " + std::to_string(count) + " numbers" : "must be a list of numbers");
  }
  std::vector<double> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    out.push_back(list_number(map, map.key_path(key) + "[" + std::to_string(i) + "]", node[i]));
  }
  return out;
}

/// A list of `count` eigenvalues written as [re, im] pairs.
std::vector<std::complex<double>> eigenvalue_list(ConfigMap& map, const std::string& key, std::size_t count) {
  const YAML::Node node = map.get_node(key);
  if (!node.IsSequence() || node.size() != count) {
    map.fail(key, "must be a list of " + std::to_string(count) + " eigenvalues written [re, im]");
  }
  std::vector<std::complex<double>> out;
  for (std::size_t i = 0; i < node.size(); ++i) {
    const std::string path = map.key_path(key) + "[" + std::to_string(i) + "]";
    const YAML::Node pair = node[i];
    if (!pair.IsSequence() || pair.size() != 2) {
      throw ConfigError(map.file(), path, yaml_text(pair), "must be [re, im]", line_of(pair));
    }
    out.emplace_back(list_number(map, path + "[0]", pair[0]), list_number(map, path + "[1]", pair[1]));
  }
  return out;
}

std::array<double, 2> pair_of(ConfigMap& map, const std::string& key) {
  const std::vector<double> v = number_list(map, key, 2);
  return {v[0], v[1]};
}

bool is_power_of_two(long long n) { return n > 0 && (n & (n - 1)) == 0; }

}  // namespace

const std::vector<std::string>& ce500_output_names() {
  static const std::vector<std::string> names = {"beta", "phi", "p_hat", "r_hat", "a_y"};
  return names;
}

namespace {

/// The flight condition; the inertia must be positive definite.
void read_flight_condition(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("flight_condition");
  auto& f = c.flight;
  f.V_mps = m.get_double("V_mps", Range::positive());
  f.S_m2 = m.get_double("S_m2", Range::positive());
  f.b_m = m.get_double("b_m", Range::positive());
  f.mu_b = m.get_double("mu_b", Range::positive());
  f.KX2 = m.get_double("KX2", Range::positive());
  f.KZ2 = m.get_double("KZ2", Range::positive());
  f.KXZ = m.get_double("KXZ");
  f.CL = m.get_double("CL", Range::non_negative());
  if (!(f.KX2 * f.KZ2 - f.KXZ * f.KXZ > 0.0)) {
    m.fail("KXZ", "must satisfy KX2 KZ2 - KXZ^2 > 0 (a positive-definite inertia), KX2 KZ2 = " +
                      std::to_string(f.KX2 * f.KZ2));
  }
  m.finish();
}

/// The stability and control derivatives.
void read_derivatives(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("derivatives");
  auto& d = c.derivatives;
  d.CYb = m.get_double("CYb");
  d.CYp = m.get_double("CYp");
  d.CYr = m.get_double("CYr");
  d.CYda = m.get_double("CYda");
  d.CYdr = m.get_double("CYdr");
  d.Clb = m.get_double("Clb");
  d.Clp = m.get_double("Clp");
  d.Clr = m.get_double("Clr");
  d.Clda = m.get_double("Clda");
  d.Cldr = m.get_double("Cldr");
  d.Cnb = m.get_double("Cnb");
  d.Cnp = m.get_double("Cnp");
  d.Cnr = m.get_double("Cnr");
  d.Cnda = m.get_double("Cnda");
  d.Cndr = m.get_double("Cndr");
  m.finish();
}

/// The gust derivatives, each as a ratio to its rate derivative.
void read_gust_derivatives(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("gust_derivatives");
  auto& d = c.derivatives;
  d.Clpw_per_Clp = m.get_double("Clpw_per_Clp");
  d.Cnpw_per_Cnp = m.get_double("Cnpw_per_Cnp");
  d.Clrw_per_Clr = m.get_double("Clrw_per_Clr");
  d.Cnrw_per_Cnr = m.get_double("Cnrw_per_Cnr");
  m.finish();
}

/// The turbulence's scale, intensities and the time constants of its filters.
void read_turbulence(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("turbulence");
  auto& t = c.turbulence;
  t.Lg_m = m.get_double("Lg_m", Range::positive());
  t.sigma_ug_mps = m.get_double("sigma_ug_mps", Range::positive());
  t.sigma_vg_mps = m.get_double("sigma_vg_mps", Range::positive());
  t.sigma_wg_mps = m.get_double("sigma_wg_mps", Range::positive());
  t.Iug0_factor = m.get_double("Iug0_per_sigma_over_V_sq", Range::positive());
  t.Iag0_factor = m.get_double("Iag0_per_sigma_over_V_sq", Range::positive());
  for (int i = 0; i < 6; ++i) {
    // tau3 and tau6 are numerator time constants (may be 0); the others set poles (> 0).
    const bool numerator = (i == 2 || i == 5);
    t.tau[static_cast<std::size_t>(i)] =
        m.get_double("tau" + std::to_string(i + 1), numerator ? Range::non_negative() : Range::positive());
  }
  m.finish();
}

/// Which gust components drive the model, and how hard.
void read_excitation(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("excitation");
  c.excitation.u_g = m.get_bool("u_g");
  c.excitation.v_g = m.get_bool("v_g");
  c.excitation.w_g = m.get_bool("w_g");
  c.excitation.intensity = m.get_double("intensity", Range::positive());
  if (!c.excitation.u_g && !c.excitation.v_g && !c.excitation.w_g) {
    m.fail("w_g", "at least one of u_g, v_g, w_g must be true (nothing would drive the model)");
  }
  m.finish();
}

/// The simulation's step, length, seed and Welch segment.
void read_simulation(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("simulation");
  auto& s = c.simulation;
  s.dt_s = m.get_double("dt_s", Range{0.0, 1.0, true, false});
  s.duration_s = m.get_double("duration_s", Range::positive());
  s.seed = static_cast<std::uint64_t>(m.get_int("seed", Range::closed(0.0, 9.0e15)));
  const long long seg = m.get_int("welch_segment", Range::closed(0.0, 1 << 24));
  if (seg != 0 && (!is_power_of_two(seg) || seg < 8)) m.fail("welch_segment", "must be 0 or a power of two >= 8");
  s.welch_segment = static_cast<std::size_t>(seg);
  if (s.duration_s / s.dt_s < 64.0) m.fail("duration_s", "must hold at least 64 time steps of dt_s");
  m.finish();
}

/// The published figures the analysis is compared with: tables 2.1 and 5.1.
void read_published(ConfigMap& root, Ce500Config& c) {
  ConfigMap m = root.get_map("published");
  {
    ConfigMap t = m.get_map("table_2_1");
    c.published.eigenvalue_tolerance = t.get_double("tolerance", Range::positive());
    c.published.uncontrolled = eigenvalue_list(t, "uncontrolled", 10);
    c.published.controlled = eigenvalue_list(t, "controlled", 10);
    c.published.reduced = eigenvalue_list(t, "reduced", 10);
    t.finish();
  }
  c.published.record_length_s = m.get_double("record_length_s", Range::positive());
  {
    ConfigMap t = m.get_map("table_5_1");
    for (const auto& name : ce500_output_names()) {
      ConfigMap r = t.get_map(name);
      PublishedVarianceRow row;
      row.analytical = pair_of(r, "analytical");
      row.fft = pair_of(r, "fft");
      row.pwelch = pair_of(r, "pwelch");
      row.var = pair_of(r, "var");
      r.finish();
      c.published.table_5_1[name] = row;
    }
    t.finish();
  }
  m.finish();
}

}  // namespace

Ce500Config ce500_config_from_map(ConfigMap& root) {
  Ce500Config c;
  c.file = root.file();
  read_flight_condition(root, c);
  read_derivatives(root, c);
  read_gust_derivatives(root, c);
  read_turbulence(root, c);
  read_excitation(root, c);
  {
    ConfigMap m = root.get_map("roll_damper");
    c.K_phi = m.get_double("K_phi");
    c.K_p = m.get_double("K_p");
    m.finish();
  }
  {
    ConfigMap m = root.get_map("reduced");
    const std::string g = m.get_enum("gust_columns", {"moment_rows", "full_model_rows"});
    c.reduced_gust_columns = g == "moment_rows" ? ReducedGustColumns::kMomentRows : ReducedGustColumns::kFullModelRows;
    m.finish();
  }
  read_simulation(root, c);
  read_published(root, c);
  root.finish();
  return c;
}

Ce500Config load_ce500_config(const std::string& file) {
  ConfigMap root = ConfigMap::load_file(file);
  return ce500_config_from_map(root);
}

}  // namespace nimble::turbulence
