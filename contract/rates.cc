#include "contract/rates.h"

#include <cmath>
#include <cstdint>
#include <vector>

#include "contract/channels.h"
#include "contract/lockstep_schedule.h"

namespace nimble::contract {

using namespace channels;

std::vector<ScheduledParticipant> lockstep_participants(const ProcessRates& rates, const RunShape& run) {
  std::vector<ScheduledParticipant> participants;
  const auto every = [](double hz) { return ScheduledParticipant{std::llround(1e9 / hz), true}; };
  if (rates.controller_hz > 0) participants.push_back(every(rates.controller_hz));
  if (rates.can_link) {  // both sides of the bridge are due at every control cycle
    participants.push_back(every(rates.controller_hz));
    participants.push_back(every(rates.controller_hz));
  }
  if (rates.mocap_hz > 0) participants.push_back(every(rates.mocap_hz));
  if (rates.estimator_hz > 0) participants.push_back(every(rates.estimator_hz));
  // The launcher's recorder, when it takes part, is next due one period after each tick.
  if (run.logger_period_ms > 0) participants.push_back({std::llround(run.logger_period_ms * 1e6), false});
  return participants;
}

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
    // participant acknowledges: the master's own schedule, replayed over one simulated second.
    const LockstepCounts c =
        replay_lockstep(std::llround(1e9 / rates.plant_hz), lockstep_participants(rates, run), 1000000000LL);
    hz[kRigClock] = static_cast<double>(c.ticks);
    hz[kStepAck] = static_cast<double>(c.acks);
  }
  const double n = static_cast<double>(run.processes);
  hz[kHeartbeat] = 2.0 * n;
  hz[kTimingHealth] = 1.0 * n;
  return hz;
}

}  // namespace nimble::contract
