#include "controller/reference_generator.h"

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <string>

namespace nimble {
namespace {

void require_positive(const char* name, double value) {
  if (!(std::isfinite(value) && value > 0.0)) {
    throw std::invalid_argument(std::string("reference generator: ") + name + " must be > 0 and finite, got " +
                                std::to_string(value));
  }
}

}  // namespace

void validate(const ReferenceGeneratorConfig& config) {
  require_positive("omega_radps", config.omega_radps);
  if (!(std::isfinite(config.zeta) && config.zeta >= 0.0)) {
    throw std::invalid_argument("reference generator: zeta must be >= 0 and finite, got " +
                                std::to_string(config.zeta));
  }
  require_positive("rate_max_radps", config.rate_max_radps);
  require_positive("accel_max_radps2", config.accel_max_radps2);
  require_positive("setpoint_max_rad", config.setpoint_max_rad);
}

ReferenceGenerator::ReferenceGenerator(const ReferenceGeneratorConfig& config, double dt_s)
    : config_(config), dt_s_(dt_s) {
  validate(config_);
  require_positive("dt_s", dt_s);
}

void ReferenceGenerator::reset(double angle_rad) {
  state_ = ReferenceState{};
  state_.angle_rad = std::isfinite(angle_rad) ? angle_rad : 0.0;
  last_setpoint_rad_ = state_.angle_rad;
}

const ReferenceState& ReferenceGenerator::step(double setpoint_rad) {
  double sp = setpoint_rad;
  if (!std::isfinite(sp)) {
    sp = last_setpoint_rad_;
    ++setpoint_clamp_count_;
  } else if (std::fabs(sp) > config_.setpoint_max_rad) {
    sp = std::clamp(sp, -config_.setpoint_max_rad, config_.setpoint_max_rad);
    ++setpoint_clamp_count_;
  }
  last_setpoint_rad_ = sp;

  // Integrate with the acceleration and rate of the previous step (onboard order).
  state_.angle_rad += state_.rate_radps * dt_s_;
  state_.rate_radps += state_.accel_radps2 * dt_s_;

  const double w = config_.omega_radps;
  double accel = -2.0 * config_.zeta * w * state_.rate_radps - w * w * (state_.angle_rad - sp);
  accel = std::clamp(accel, -config_.accel_max_radps2, config_.accel_max_radps2);

  const double rmax = config_.rate_max_radps;
  if (state_.rate_radps >= rmax) {
    state_.rate_radps = rmax;
    if (accel > 0.0) accel = 0.0;
  } else if (state_.rate_radps <= -rmax) {
    state_.rate_radps = -rmax;
    if (accel < 0.0) accel = 0.0;
  }
  state_.accel_radps2 = accel;
  return state_;
}

}  // namespace nimble
