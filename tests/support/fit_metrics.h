#pragma once
// The identification system test's bounds on the fit of p_dot and v_dot* (r_xy > 0.9, R^2 > 0.8,
// RMSE below 10 % of the range), checked on a `rig identify --json` report; shared by the tests
// that hold identifications to them.

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

namespace nimble::test {

inline void check_fit_metrics(const YAML::Node& report) {
  for (const char* out : {"p_dot", "v_dot_star"}) {
    const YAML::Node m = report["metrics"][out];
    INFO(out << ": r_xy " << m["rxy"].as<double>() << ", R2 " << m["r2"].as<double>() << ", RMSE "
             << m["rmse_pct_range"].as<double>() << " % of range");
    CHECK(m["rxy"].as<double>() > 0.9);
    CHECK(m["r2"].as<double>() > 0.8);
    CHECK(m["rmse_pct_range"].as<double>() < 10.0);
  }
}

}  // namespace nimble::test
