#pragma once
/// Nominal rates of the rig's channels as a function of the configured process rates. The
/// numbers come from the scenario's sections (launcher/scenario_check.cc loads them with the same
/// loaders the processes use); this library only derives the channel rates from them.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "contract/default_rates.h"
#include "contract/lockstep_schedule.h"

namespace nimble::contract {

/// Rates the processes of a scenario run at [Hz].
struct ProcessRates {
  double plant_hz = 0.0;       ///< plant.rate_hz: the integration step, the lockstep step
  double truth_hz = 0.0;       ///< plant.truth_rate_hz: TRUTH
  double feedback_hz = 0.0;    ///< plant.feedback_rate_hz: ACTUATOR_FB (and ACTUATOR_FB_CAN)
  double imu_hz = 0.0;         ///< sensing.imu.sample_rate_hz: IMU
  double controller_hz = 0.0;  ///< controller.rate_hz; 0 if the scenario has no controller
  double mocap_hz = 0.0;       ///< sensing.mocap.frame_rate_hz; 0 if the scenario has no mocap emulator
  double estimator_hz = 0.0;   ///< ESTIMATE (one per IMU sample); 0 if the scenario has no estimator
  bool can_link = false;       ///< actuator_link: can (the two sides of the CAN bridge run)
  double can_health_hz = 0.0;  ///< can_bridge.health_rate_hz: CAN_HEALTH of each side (wall clock)
};

/// How the run is clocked, for the rates that depend on it.
struct RunShape {
  bool lockstep = false;
  double logger_period_ms = 10.0;  ///< lockstep.logger_period_ms: the launcher's logger acknowledges this
                                   ///< often; 0: the logger is no participant (in process)
  std::size_t processes = 0;       ///< rig processes in the run (each sends HEARTBEAT and TIMING_HEALTH)
};

/// The lockstep participants of a run and their schedule (rig processes with a task, both
/// CAN bridge sides over the CAN link, the launcher's recorder when it takes part).
std::vector<ScheduledParticipant> lockstep_participants(const ProcessRates& rates, const RunShape& run);

/// Expected rate of each channel [Hz]: simulated-time rates for stream channels, wall-clock
/// rates summed over the publishers for the wall-clock channels. In lockstep RIG_CLOCK and
/// STEP_ACK follow the plant's rule (a tick at each step where a participant is due, one
/// acknowledgement per due participant), replayed over one simulated second. Channels
/// without a fixed rate (RUN_CONTROL, FAULT) are absent.
std::map<std::string, double> expected_rates(const ProcessRates& rates, const RunShape& run);

}  // namespace nimble::contract
