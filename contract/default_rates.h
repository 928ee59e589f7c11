#pragma once
/// The default rates of the rig's configuration sections: a header of constants only, for the
/// sections' structs in every room.

namespace nimble::contract {

/// The rates of the rig's streams when a scenario does not set them [Hz]: the defaults of the
/// configuration sections' rates, written once here (the sections' structs and the tools that
/// stand in for them take them from here).
/// The onboard IMU's sample rate (thesis Section 8.1: 512 Hz; the thesis's fusion data were
/// upsampled to it): `sensing.imu.sample_rate_hz`.
inline constexpr double kDefaultImuRateHz = 512.0;
/// The control rate of the onboard loop, the IMU's rate (the loop runs on its samples):
/// `controller.rate_hz`'s default, and so the rate of ACTUATOR_CMD and of the CAN bridge's cycle
/// when a scenario does not set it.
inline constexpr double kDefaultControlRateHz = kDefaultImuRateHz;
/// The motion-capture frame rate (thesis Section 8.1: 200 Hz): `sensing.mocap.frame_rate_hz`.
inline constexpr double kDefaultMocapFrameRateHz = 200.0;
/// The plant's integration rate, the lockstep step (1 ms: well inside the flap actuator's 80 ms
/// time constant, thesis Eq 33, and the 59 ms period of the 17 Hz flapping): `plant.rate_hz`, and the linear loop's step.
inline constexpr double kDefaultPlantRateHz = 1000.0;
/// TRUTH's rate, every plant step: `plant.truth_rate_hz`.
inline constexpr double kDefaultTruthRateHz = kDefaultPlantRateHz;
/// ACTUATOR_FB's rate (the servo feedback a lab's telemetry carries): `plant.feedback_rate_hz`.
inline constexpr double kDefaultFeedbackRateHz = 100.0;
/// CAN_HEALTH's rate per bridge side, per wall second: `can_bridge.health_rate_hz`.
inline constexpr double kDefaultCanHealthRateHz = 2.0;
/// The control rates a scenario may set (`controller.rate_hz`) [Hz]: the controller's parameter
/// table and every other reader of the value check it against these.
inline constexpr double kMinControlRateHz = 50.0;
inline constexpr double kMaxControlRateHz = 5000.0;

}  // namespace nimble::contract
