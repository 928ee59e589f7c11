#include "contract/rates.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "contract/channels.h"

namespace nimble::contract {

using namespace channels;

std::map<std::string, double> expected_rates(const ProcessRates& rates, const RunShape& run) {
  std::map<std::string, double> hz;
  hz[kTruth] = rates.truth_hz;
  hz[kActuatorFeedback] = rates.feedback_hz;
  hz[kImu] = rates.imu_hz;
  if (rates.controller_hz > 0) {
    hz[kActuatorCommand] = rates.controller_hz;
    hz[kControllerStatus] = rates.controller_hz;
    hz[kAttitudeSetpoint] = rates.controller_hz;
  }
  if (rates.mocap_hz > 0) hz[kMocapPose] = rates.mocap_hz;
  if (rates.estimator_hz > 0) hz[kEstimate] = rates.estimator_hz;
  if (rates.can_link) {
    hz[kActuatorCommandCan] = rates.controller_hz;
    hz[kActuatorFeedbackCan] = rates.feedback_hz;
    hz[kCanHealth] = 2.0 * rates.can_health_hz;
  }
  if (run.lockstep) {
    // RIG_CLOCK goes out at the plant steps where a participant is due, and every due
    // participant acknowledges: replay the plant's rule over one simulated second.
    const int64_t dt = std::llround(1e9 / rates.plant_hz);
    const int64_t logger_period = std::llround(run.logger_period_ms * 1e6);
    std::vector<int64_t> periods;
    if (rates.controller_hz > 0) periods.push_back(std::llround(1e9 / rates.controller_hz));
    if (rates.can_link) {  // both sides of the bridge are due at every control cycle
      periods.push_back(std::llround(1e9 / rates.controller_hz));
      periods.push_back(std::llround(1e9 / rates.controller_hz));
    }
    if (rates.mocap_hz > 0) periods.push_back(std::llround(1e9 / rates.mocap_hz));
    if (rates.estimator_hz > 0) periods.push_back(std::llround(1e9 / rates.estimator_hz));
    std::vector<int64_t> next(periods.size(), 0);
    int64_t logger_next = 0, ticks = 0, acks = 0;
    for (int64_t t = 0; t < 1000000000LL; t += dt) {
      const bool logger = logger_period > 0;  // the launcher's recorder acknowledges too
      bool due = logger && logger_next <= t;
      for (const int64_t n : next) due = due || n <= t;
      if (!due) continue;
      ++ticks;
      for (std::size_t i = 0; i < periods.size(); ++i) {
        if (next[i] <= t) {
          ++acks;
          next[i] = (t / periods[i] + 1) * periods[i];
        }
      }
      if (logger && logger_next <= t) {
        ++acks;
        logger_next = t + logger_period;
      }
    }
    hz[kRigClock] = static_cast<double>(ticks);
    hz[kStepAck] = static_cast<double>(acks);
  }
  const double n = static_cast<double>(run.processes);
  hz[kHeartbeat] = 2.0 * n;
  hz[kTimingHealth] = 1.0 * n;
  return hz;
}

}  // namespace nimble::contract
