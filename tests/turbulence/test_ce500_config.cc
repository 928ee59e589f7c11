// Loading and validating rig_configs/turbulence/ce500_practical.yaml.

#include <fstream>
#include <sstream>
#include <string>

#include <catch2/catch.hpp>

#include "../support/config_error.h"
#include "test_support.h"
#include "turbulence/ce500_config.h"

using namespace nimble::turbulence;

namespace {

std::string practical_text() {
  std::ifstream in(nimble::turbulence::test::practical_file());
  std::stringstream s;
  s << in.rdbuf();
  return s.str();
}

/// The practical's text with `from` replaced by `to` (which must occur).
std::string edited(const std::string& from, const std::string& to) {
  std::string text = practical_text();
  const std::size_t at = text.find(from);
  REQUIRE(at != std::string::npos);
  return text.replace(at, from.size(), to);
}

void load_inline(const std::string& text) {
  nimble::ConfigMap map = nimble::ConfigMap::load_string(text, "inline.yaml");
  ce500_config_from_map(map);
}

}  // namespace

TEST_CASE("The practical file loads with the paper-facts values", "[turbulence][config]") {
  const Ce500Config& c = nimble::turbulence::test::practical();
  CHECK(c.flight.V_mps == 51.4);
  CHECK(c.flight.b_m == 13.36);
  CHECK(c.flight.mu_b == 13.0);
  CHECK(c.derivatives.Cnr == -0.1930);
  CHECK(c.derivatives.Clrw_per_Clr == 0.7);
  CHECK(c.turbulence.tau[5] == 0.2243);
  CHECK(c.turbulence.Lg_m == 150.0);
  CHECK(c.K_phi == -0.1);
  CHECK(c.simulation.dt_s == 0.05);
  CHECK(!c.excitation.u_g);
  CHECK(c.published.controlled.size() == 10);
  CHECK(c.published.table_5_1.at("a_y").var[1] == 0.1287);
}

TEST_CASE("Ce500 config errors name the file, the key and the value", "[turbulence][config]") {
  using nimble::test::expect_inline_key_error;
  expect_inline_key_error(load_inline, edited("V_mps: 51.4", "V_mps: -51.4"), "flight_condition.V_mps", "-51.4");
  expect_inline_key_error(load_inline, edited("  CYb: -0.9896\n", ""), "derivatives.CYb");
  expect_inline_key_error(load_inline, edited("tau5: 0.3294", "tau5: fast"), "turbulence.tau5", "fast");
  expect_inline_key_error(load_inline, edited("KXZ: 0.002", "KXZ: 0.9"), "flight_condition.KXZ", "0.9");
  expect_inline_key_error(load_inline, edited("K_p: 0.0", "K_p: 0.0\n  K_r: 0.0"), "roll_damper.K_r", "0.0");
  expect_inline_key_error(load_inline, edited("gust_columns: full_model_rows", "gust_columns: all"),
                          "reduced.gust_columns", "all");
  expect_inline_key_error(load_inline, edited("welch_segment: 0", "welch_segment: 1000"), "simulation.welch_segment",
                          "1000");
  expect_inline_key_error(load_inline, edited("[-0.4799, 0]", "[-0.4799, x]"), "published.table_2_1.controlled[4][1]",
                          "x");
  expect_inline_key_error(load_inline, edited("var: [0.1128, 0.1287]", "var: [0.1128]"), "published.table_5_1.a_y.var");
}
