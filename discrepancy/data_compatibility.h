#pragma once
/// Data compatibility: are the sensors telling the truth? The first stage of the discrepancy
/// workflow (discrepancy/discrepancy.h), run on every flight before any aerodynamic term is tried
/// (Klein & Morelli, Aircraft System Identification, ch. 10; TU Delft's flight path
/// reconstruction). docs/discrepancy.md "Data compatibility" has the method and its figures.
///
/// The kinematic relation of the lateral set holds whatever the aerodynamics:
///     phi_dot = p + tan(theta) (q sin(phi) + r cos(phi))   (the last term where q, r, theta are recorded)
/// A rate gyro that reads (1 + k) times the true rate plus a bias b, on a clock that stamps its
/// samples tau later than the attitude's source (the motion capture), records
///     p_rec(t) = (1 + k) p(t - tau) + b,   so   phi_dot(t) = a p_rec(t + tau) + c,
/// a = 1 / (1 + k), c = -b / (1 + k). On the record low-passed as for identification, phi_dot is
/// regressed on the gyro side shifted by tau (scanned over whole samples, then refined by one
/// Gauss-Newton step: the shifted signal's derivative as a regressor; a clock that runs fast or slow,
/// tau(t) = tau + d (t - t_mid), by that derivative times t - t_mid), so a, tau, d and c come with a
/// covariance that allows coloured residuals (batch means; discrepancy_parts.h). Per error:
///   - significant: its excess over the tolerance (below: what the record resolves, or what a
///     calibrated sensor keeps) is tested by its Wald statistic at the workflow's p_critical
///     (Hotelling's tail from the blocks), each of the three an alarm test of AlarmRule;
///   - signature: a scale error grows with the signal (a fitted on the samples of small and of
///     large |p| agree), a time offset is a phase lag growing linearly with frequency (tau fitted
///     below and above the median frequency of p agree), a bias is constant (c fitted on the two
///     halves of the record agree), a clock drift is even (d on the two halves agree); each
///     comparison a two-sided test at signature_alpha whose difference must also exceed the
///     tolerance to count;
///   - named (sensor_scale, time_offset, clock_drift, sensor_bias) when both hold, with a 95 %
///     interval. The drift's tolerance is the one that moves the offset by its own tolerance over
///     the record.
/// A significant error is corrected in the record (the gyro's samples restamped by -tau and the
/// drift, p unbiased and unscaled) before the aerodynamic search, named or not: what the kinematics
/// show is not for L and Y to explain. An offset is taken out below its tolerance too once it is
/// told from zero at signature_alpha (the aerodynamic search would see what is left as a lag of the
/// flap input). One whose signature fails is reported as structure (verdict `unexplained`), not
/// named.

#include <cstddef>
#include <map>
#include <string>
#include <vector>

#include "ident/flight_data.h"
#include "ident/signal.h"
#include "effects/sensor_bias.h"

namespace nimble::ident {

/// Options of the compatibility stage (DiscrepancyOptions::compatibility).
struct CompatibilityOptions {
  bool enabled = true;
  /// The time offsets scanned: -max_offset_s .. +max_offset_s [s]. A lab's unsynchronised
  /// on-board and motion-capture records differ by tens of ms (the thesis's flights had to be
  /// synchronised, Section 8.1); 0.2 s covers that with room.
  double max_offset_s = 0.2;
  /// A scale error within this fraction is not named: the level a lab's calibration of a MEMS
  /// gyro reaches (assumption; an uncalibrated MPU-6000 is specified to +-3 %).
  double scale_tolerance = 0.01;
  /// A bias within this is not named [rad/s]: the gyro's accuracy, 0.05 deg/s (thesis Section
  /// 8.1, the on-board IMU).
  double bias_tolerance_radps = 8.7266e-4;
  /// A time offset within this is not named [s]; 0: one sample period of the coarser of the two
  /// sources (the gyro's and the attitude's median sample interval), below which their stamps
  /// do not resolve an instant.
  double time_tolerance_s = 0.0;
  /// Level of each signature comparison (two-sided); as the workflow's gust_band_alpha.
  double signature_alpha = 0.01;
  /// The channels of the IMU's clock: restamped together when a time offset is found.
  std::vector<std::string> imu_channels{"p", "q", "r", "ax", "ay", "az"};
};

/// The sensor errors' names. The rate gyro's bias is the effect sensor_bias (effects/sensor_bias.h)
/// found before any aerodynamic name, and carries its name.
inline const std::string kSensorScaleError = "sensor_scale";
inline const std::string kTimeOffsetError = "time_offset";
inline const std::string kClockDriftError = "clock_drift";
inline const std::string& kSensorBiasError = effects::kSensorBiasName;

/// One sensor error estimated from the kinematics.
struct SensorError {
  std::string name;     ///< kSensorScaleError, kTimeOffsetError, kClockDriftError or kSensorBiasError
  std::string channel;  ///< the sensor's channel ("p")
  std::string against;  ///< the source it is compared with ("phi": the attitude)
  std::string unit;     ///< "-" (a fraction), "s", "ppm", "rad/s"
  /// k; tau at t_mid_s (positive: the gyro's stamps are late); the drift d of tau per second of the
  /// record (tau(t) = tau + d (t - t_mid_s)) [ppm]; b.
  double value = 0.0;
  double sigma = 0.0;               ///< coloured-residual standard deviation
  double interval[2] = {0.0, 0.0};  ///< 95 % (Student's t on the batch-means blocks)
  double tolerance = 0.0;           ///< the excess over this is tested
  double p_value = 1.0;             ///< of the excess, against p_critical
  bool significant = false;
  bool signature_holds = true;
  std::string signature_note;  ///< the comparison's figures
  bool named = false;          ///< significant and its signature holds
  bool corrected = false;      ///< the record was corrected for it (significant; an offset told from zero)
};

/// The stage's result for one flight.
struct CompatibilityResult {
  std::string source;
  bool ran = false;
  std::string note;      ///< why it did not run, when it did not
  std::string equation;  ///< the kinematic relation used
  std::size_t samples = 0;
  double t_mid_s = 0.0;             ///< the middle of the rows checked: the time about which a clock drift acts
  double blocks = 0.0;              ///< batch-means blocks of the coloured covariance
  std::vector<SensorError> errors;  ///< sensor_scale, time_offset, sensor_bias, clock_drift (every one tested)
  /// Held-out gap of the kinematic relation (mean squared error over the variance of phi_dot, every
  /// fold predicted by the fit on the others): as recorded (a = 1, tau = 0, c = 0) and corrected.
  double kinematic_gap_before = 0.0, kinematic_gap_after = 0.0;
  /// When a correction was made: the baseline structure's held-out RMSE per equation output
  /// ("p_dot", "v_dot_star", "delta_f_dot"; DiscrepancyResult::gap's units) on the record as
  /// recorded, to set beside the gap table's rmse_before on the corrected record. (Not the
  /// normalised gap: v_dot_star contains p, so its variance changes with the correction.)
  std::map<std::string, double> rmse_uncorrected;
  std::vector<std::string> corrections;  ///< what was corrected, in words
  double elapsed_ms = 0.0;               ///< the stage's own time in the workflow: check, correction, RMSE as recorded
};

/// Runs the stage on one flight. p_critical: the alarm rule's tail; folds: of the held-out gap;
/// min_block: the batch rule's smallest block [samples]. A record without p and phi, or whose p
/// is not excited, is not checked (ran = false, note says why).
CompatibilityResult check_compatibility(const FlightData& data, const ProcessingOptions& processing,
                                        const CompatibilityOptions& options, double p_critical, std::size_t folds,
                                        std::size_t min_block);

/// The record corrected for the result's significant errors (a copy; `data` itself if none).
FlightData corrected_record(const FlightData& data, const CompatibilityResult& result,
                            const CompatibilityOptions& options);

}  // namespace nimble::ident
