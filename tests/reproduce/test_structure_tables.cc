// The model-structure tables of rig reproduce thesis (reproduce/structure_tables.h): eigenvector
// cells in the thesis's form, correlation cells, the model files' tables, and the rounding the
// campaign file's numbers carry.

#include <cmath>
#include <string>

#include <catch2/catch.hpp>

#include "core/model.h"
#include "core/modes.h"
#include "core/vehicle.h"
#include "reproduce/campaign_spec.h"
#include "reproduce/structure_tables.h"

using namespace nimble;
using namespace nimble::reproduce;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

CellMap eigenvector_cells(const std::string& model_file) {
  const DerivativeModel m = load_model(model_file);
  const Vehicle v = load_vehicle(m.vehicle_file);
  const StateSpace ss = build_state_space(m, v);
  CellMap cells;
  put_eigenvectors(cells, ss, analyse_modes(ss, v));
  return cells;
}

}  // namespace

TEST_CASE("structure tables: eigenvectors as Table 8.13 prints them, a real mode's phase as its sign", "[structure]") {
  const CellMap c = eigenvector_cells(kConfigs + "models/nimble_lateral_set1.yaml");
  // Table 8.13: p 0.30 (180 deg) and 0.16 (83.4 deg); v 0.86 (180 deg) and 0.70 (-53.5 deg).
  CHECK(c.at("p+ / mode 1") == Approx(-0.30).margin(0.01));
  CHECK(c.at("v+ / mode 1") == Approx(-0.86).margin(0.01));
  CHECK(c.at("p+ / mode 2") == Approx(0.16).margin(0.01));
  CHECK(c.at("p+ / mode 2 phase") == Approx(83.4).margin(0.5));
  CHECK(c.at("v+ / mode 2 phase") == Approx(-53.5).margin(0.5));
  // The real mode has no phase cell; the roll angle (1 at 0 deg by construction) none at all.
  CHECK(c.count("p+ / mode 1 phase") == 0);
  for (const auto& [key, value] : c) CHECK(key.rfind("phi+", 0) != 0);
  CHECK(c.size() == 6);
}

TEST_CASE("structure tables: the four-state file's yaw mode as Table 8.9, r+ at 180 deg", "[structure]") {
  const CellMap c = eigenvector_cells(kConfigs + "models/nimble_lateral4_yaw.yaml");
  CHECK(c.at("r+ / mode 3") == Approx(-2.08).margin(0.01));
  CHECK(c.at("v+ / mode 3") == Approx(0.94).margin(0.01));
  CHECK(c.at("r+ / mode 2 phase") == Approx(-70.4).margin(0.1));
  CHECK(c.size() == 12);
}

TEST_CASE("structure tables: |rho| of every pair of an equation, under either order of the pair", "[structure]") {
  ident::IdentResult r;
  ident::EquationResult eq;
  eq.equation.name = "L";
  eq.equation.parameters = {"Lp", "Lv", "L_df"};
  eq.correlation.resize(3, 3);
  eq.correlation << 1.0, -0.65, 0.8, -0.65, 1.0, 0.18, 0.8, 0.18, 1.0;
  r.regression.equations.push_back(eq);
  eq.equation.name = "Y";
  eq.equation.parameters = {"Yp", "Yv", "Y_df"};
  r.regression.equations.push_back(eq);
  CellMap c;
  put_correlations(c, r, "L");
  CHECK(c.size() == 6);  // three pairs, both orders; no diagonal
  CHECK(c.at("Lp / Lv") == Approx(0.65));
  CHECK(c.at("Lv / Lp") == Approx(0.65));
  CHECK(c.at("L_df / Lv") == Approx(0.18));
  CHECK(c.count("Lp / Lp") == 0);
  CHECK(c.count("Yp / Yv") == 0);
}

TEST_CASE("structure tables: the model files' tables, and D's rows judged against the plant file", "[structure]") {
  const CampaignSpec spec = load_campaign(kConfigs + "reproduce/thesis.yaml");
  const auto t = structure_model_tables(spec);
  const DerivativeModel lat4 = load_model(spec.lateral4_model);
  const DerivativeModel set1 = load_model(spec.sets.front().model);
  for (const char* row : {"OLS", "WLS"}) {
    CHECK(t.at(kPlantDerivativesD1).at(std::string(row) + " / Nr") == lat4.derivatives.at("Nr"));
    CHECK(t.at(kPlantDerivativesD2).at(std::string(row) + " / L_dt") == set1.derivatives.at("L_dt"));
  }
  CHECK(t.at("E.2-model").at("set 1 / Lv") == Approx(-6.69e-4));
  CHECK(t.at("E.3-model").at("set 1 / Y_dd") == Approx(-5.41e-2));
  CHECK(t.at("8.13-model").at("v+ / mode 2") == Approx(0.7065).margin(0.001));
  // Every published cell of these tables has the rig's value.
  for (const char* id : {"8.9-model", "8.13-model", "E.2-model", "E.3-model"}) {
    for (const auto& [row, columns] : spec.tables.at(id).published) {
      for (const auto& [column, value] : columns) {
        INFO(id << " " << row << " / " << column);
        CHECK(t.at(id).count(row + " / " + column) == 1);
      }
    }
  }
  // A pipeline check's tolerance is the printed number's last digit: -1.44e-7 and -6.00e-2 as written.
  CHECK(spec.tables.at("D.1").printed_half_digit.at("WLS").at("N_df") == Approx(5e-10));
  CHECK(spec.tables.at("E.3").printed_half_digit.at("set 1").at("Yv") == Approx(5e-5));
  CHECK(spec.tables.at("8.13").reference_table == "8.13-model");
  CHECK(spec.tables.at("8.14").reference_table == "9.5-model");
  CHECK(category_of(table_source("H.4")) == Category::kFlights);
  CHECK(category_of(table_source("8.15")) == Category::kModel);
}
