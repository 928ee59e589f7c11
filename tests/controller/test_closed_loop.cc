// Closed-loop tests on the linear set-1 model with the calibrated roll map:
// stability with both gain sets, state and delta_f ranges against the thesis.

#include <cmath>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "controller/attitude_controller.h"
#include "controller/linear_closed_loop.h"
#include "controller/manoeuvre.h"
#include "core/model.h"
#include "core/vehicle.h"

using namespace nimble;

namespace {

const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

struct Rig {
  DerivativeModel model = load_model(kConfigs + "models/nimble_lateral_set1.yaml");
  Vehicle vehicle = load_vehicle(model.vehicle_file);
  ControllerConfig config = load_controller_config(kConfigs + "controller/nimble_attitude.yaml");
};

LinearLoopResult fly(const Rig& rig, const std::string& manoeuvre, const std::string& gain_set,
                     const ControllerConfig* config = nullptr, LinearLoopOptions options = {}) {
  const ControllerConfig& cfg = config ? *config : rig.config;
  const ManoeuvrePlayer player(load_manoeuvre(kConfigs + "manoeuvres/" + manoeuvre + ".yaml"), cfg.trim_throttle_pct);
  return simulate_linear_closed_loop(rig.model, rig.vehicle, cfg, gain_set, player, options);
}

/// ratio within [1/2, 2]
bool within_factor_2(double value, double target) { return value >= 0.5 * target && value <= 2.0 * target; }

}  // namespace

TEST_CASE("fast-gain identification train with the calibrated map matches thesis ranges", "[closed_loop]") {
  const Rig rig;
  const LinearLoopResult r = fly(rig, "id_doublet_train_7_4hz", "fast");
  INFO("ranges p " << r.p_radps.range() << " v " << r.v_mps.range() << " phi " << r.phi_rad.range() << " delta_f "
                   << r.delta_f_radps.range());
  REQUIRE(r.finite);
  CHECK(returned_to_hover(r));
  const TargetRanges t;  // Table 9.4 set 1, Table 9.10
  CHECK(within_factor_2(r.p_radps.range(), t.p_radps));
  CHECK(within_factor_2(r.v_mps.range(), t.v_mps));
  CHECK(within_factor_2(r.phi_rad.range(), t.phi_rad));
  CHECK(within_factor_2(r.delta_f_radps.range(), t.delta_f_radps));
  // The roll loop actually moved the vehicle the way the set-point asked: negative first.
  CHECK(r.phi_rad.min < -0.1);
}

TEST_CASE("slow gains fly the identification train stably and return to hover", "[closed_loop]") {
  const Rig rig;
  const LinearLoopResult r = fly(rig, "id_doublet_train_7_4hz", "slow");
  REQUIRE(r.finite);
  CHECK(returned_to_hover(r));
  // Slow gains move the vehicle less than fast gains (thesis Section 7.1).
  const LinearLoopResult fast = fly(rig, "id_doublet_train_7_4hz", "fast");
  CHECK(r.phi_rad.range() < fast.phi_rad.range());
}

TEST_CASE("the shipped map is the best of the calibration grid", "[closed_loop][calibration]") {
  const Rig rig;
  const Manoeuvre train = load_manoeuvre(kConfigs + "manoeuvres/id_doublet_train_7_4hz.yaml");
  const ManoeuvrePlayer player(train, rig.config.trim_throttle_pct);
  double best = INFINITY, shipped = INFINITY;
  for (double k = 10.0; k <= 160.0 + 1e-9; k += 5.0) {
    ControllerConfig cfg = rig.config;
    cfg.roll_cmd_to_delta_f_radps = k;
    const LinearLoopResult r = simulate_linear_closed_loop(rig.model, rig.vehicle, cfg, "fast", player);
    const double score = returned_to_hover(r) ? range_score(r) : INFINITY;
    best = std::min(best, score);
    if (std::fabs(k - rig.config.roll_cmd_to_delta_f_radps) < 1e-9) shipped = score;
  }
  INFO("best score " << best << ", shipped map " << rig.config.roll_cmd_to_delta_f_radps << " score " << shipped);
  CHECK(std::isfinite(shipped));
  CHECK(shipped <= best + 0.02);
  CHECK(shipped < 0.2);  // about 20 % per range on average (log scale)
}

TEST_CASE("both gain sets are stable over the published map interval 10..160 rad/s", "[closed_loop]") {
  const Rig rig;
  LinearLoopOptions long_tail;
  long_tail.tail_s = 40.0;  // slow gains near the lower end of the interval converge slowly
  for (const std::string gains : {"fast", "slow"}) {
    for (const double k : {10.0, 20.0, 40.0, 80.0, 160.0}) {
      ControllerConfig cfg = rig.config;
      cfg.roll_cmd_to_delta_f_radps = k;
      const LinearLoopResult r = fly(rig, "id_doublet_train_7_4hz", gains, &cfg, long_tail);
      INFO(gains << " map " << k << " settle |phi| " << r.settle_max_abs_phi_rad);
      CHECK(returned_to_hover(r));
    }
  }
}

TEST_CASE("slow gains with a too small map (5 rad/s) do not return to hover", "[closed_loop]") {
  // Linear closed loop on set 1: slow gains need more than about 8 rad/s per unit.
  const Rig rig;
  ControllerConfig cfg = rig.config;
  cfg.roll_cmd_to_delta_f_radps = 5.0;
  LinearLoopOptions long_tail;
  long_tail.tail_s = 40.0;
  const LinearLoopResult r = fly(rig, "id_doublet_train_7_4hz", "slow", &cfg, long_tail);
  CHECK_FALSE(returned_to_hover(r));
}

TEST_CASE("every shipped manoeuvre flies stably with its gain set and with the other", "[closed_loop]") {
  const Rig rig;
  for (const std::string name :
       {"hover", "ol_doublet_6hz", "ol_112_7_3p5hz", "cl_doublet_train_6_4_2hz", "cl_112_4_2hz", "coupled_doublet_6hz",
        "nonlinear_doublet_20deg", "nonlinear_doublet_30deg"}) {
    for (const std::string gains : {"fast", "slow"}) {
      const LinearLoopResult r = fly(rig, name, gains);
      INFO(name << " with " << gains << " gains: settle |phi| " << r.settle_max_abs_phi_rad << " |v| "
                << r.settle_max_abs_v_mps);
      CHECK(returned_to_hover(r));
    }
  }
}
