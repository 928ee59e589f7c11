// Unit tests of the roll tracking verdict on synthetic errors sampled as the controller's cycles
// come (512 Hz): the half-cycles the recorder makes of them, and the oscillations
// find_oscillation names and does not name (a sustained and a growing sine; a doublet's
// decaying response, a lightly damped one, noise, a sine the reference itself drives); the
// tracking bounds; how the verdict and the report carry them.

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <yaml-cpp/yaml.h>

#include "launcher/run_report.h"
#include "launcher/verdict.h"

using namespace nimble::launcher;

namespace {

constexpr double kRate = 512.0;  // the controller's cycles [Hz]

/// The summary of `error(t)` [deg] against `reference(t)` [deg] over `duration_s`.
TrackingSummary tracked(
    double duration_s, const std::function<double(double)>& error,
    const std::function<double(double)>& reference = [](double) { return 0.0; }) {
  TrackingRecorder rec;
  for (int k = 0; k <= static_cast<int>(duration_s * kRate); ++k) {
    const double t = k / kRate;
    rec.add(t, error(t), reference(t));
  }
  return rec.summary();
}

/// A free oscillation of `f_hz` starting at `amplitude_deg` with damping ratio `zeta`.
std::function<double(double)> ringing(double amplitude_deg, double f_hz, double zeta) {
  return [=](double t) {
    const double wn = 2.0 * M_PI * f_hz / std::sqrt(1.0 - zeta * zeta);
    return amplitude_deg * std::exp(-zeta * wn * t) * std::sin(2.0 * M_PI * f_hz * t);
  };
}

/// A flight that stayed within the limits (verdict.cc judges those first).
FlightSummary within_limits() {
  FlightSummary f;
  f.samples = 1000;
  f.max_abs_phi = 30.0 * M_PI / 180.0;
  return f;
}

}  // namespace

TEST_CASE("tracking: the recorder's half-cycles of a sine are its halves, at its zero crossings",
          "[launcher][tracking]") {
  const TrackingSummary s = tracked(2.0, [](double t) { return 30.0 * std::sin(2.0 * M_PI * 4.0 * t); });
  CHECK(s.samples == 1025);
  CHECK(s.rms_deg == Approx(30.0 / std::sqrt(2.0)).epsilon(0.01));
  CHECK(s.max_deg == Approx(30.0).epsilon(0.001));
  REQUIRE(s.half_cycles.size() == 16);  // 8 cycles; the last still in progress at t = 2 s
  for (std::size_t i = 1; i + 1 < s.half_cycles.size(); ++i) {
    const TrackingHalfCycle& h = s.half_cycles[i];
    CHECK(h.start_s == Approx(i * 0.125).margin(1e-6));
    CHECK(h.end_s == Approx((i + 1) * 0.125).margin(1e-6));
    CHECK(std::fabs(h.peak_deg) == Approx(30.0).epsilon(0.001));
    CHECK((h.peak_deg > 0) == (i % 2 == 0));
    CHECK(h.reference_range_deg == 0.0);
  }
  // Jitter within the dead band does not split a half-cycle.
  const TrackingSummary jittered = tracked(
      2.0, [](double t) { return 30.0 * std::sin(2.0 * M_PI * 4.0 * t) + 0.9 * std::sin(2.0 * M_PI * 200.0 * t); });
  CHECK(jittered.half_cycles.size() == 16);
}

TEST_CASE("tracking: a sustained 4 Hz sine of +-30 deg is named, with its frequency, amplitude and start",
          "[launcher][tracking]") {
  const JudgeConfig jc;
  const auto sine = [](double t) { return t < 1.0 ? 0.0 : 30.0 * std::sin(2.0 * M_PI * 4.0 * (t - 1.0)); };
  const Oscillation o = find_oscillation(tracked(6.0, sine).half_cycles, jc);
  REQUIRE(o.detected);
  CHECK_FALSE(o.growing);
  CHECK(o.frequency_hz == Approx(4.0).epsilon(0.01));
  CHECK(o.amplitude_deg == Approx(30.0).epsilon(0.01));
  CHECK(o.start_s == Approx(1.0).margin(0.01));
  CHECK(o.damping_ratio == Approx(0.0).margin(0.001));
  CHECK(o.cycles == 19);  // 20 cycles, the last one's second half still in progress
  CHECK(o.text == "roll oscillation 4.0 Hz +-30 deg sustained from t = 1.0 s");

  const TrackingVerdict tv = judge_tracking(tracked(6.0, sine), jc);
  CHECK(tv.judged);
  CHECK(tv.lost);
  CHECK(tv.rms_deg == Approx(19.36).epsilon(0.001));  // within its bound (20 deg): the oscillation alone
  CHECK(tv.text == "roll oscillation 4.0 Hz +-30 deg sustained from t = 1.0 s");
  const Verdict v = judge_run(within_limits(), jc, false, "", {}, false, "", tv);
  CHECK(v.exit_code == kRunNotTracking);
  CHECK(v.controlled);
  CHECK(v.text == "completed, " + tv.text);
}

TEST_CASE("tracking: a growing oscillation is named as growing, from where it reached the amplitude",
          "[launcher][tracking]") {
  const JudgeConfig jc;
  // 2 Hz, from 1 deg growing 30 % a cycle (damping ratio -0.042) to +-28 deg by 6.5 s.
  const double sigma = 2.0 * std::log(1.3);
  const auto growing = [sigma](double t) { return std::exp(sigma * t) * std::sin(2.0 * M_PI * 2.0 * t); };
  const Oscillation o = find_oscillation(tracked(6.6, growing).half_cycles, jc);
  REQUIRE(o.detected);
  CHECK(o.growing);
  CHECK(o.frequency_hz == Approx(2.0).epsilon(0.01));
  CHECK(o.damping_ratio ==
        Approx(-std::log(1.3) / std::sqrt(4 * M_PI * M_PI + std::pow(std::log(1.3), 2))).epsilon(0.05));
  // The first peak of 4 deg or more is the half-cycle from 2.75 s (the one before peaks at 3.96).
  CHECK(o.start_s == Approx(2.75).margin(0.001));
  CHECK(o.amplitude_deg == Approx(std::exp(sigma * 6.375)).epsilon(0.01));
  CHECK(o.text == "roll oscillation 2.0 Hz +-28 deg growing from t = 2.8 s");
  // The same oscillation saturated at +-10 deg from 4.5 s goes on as the same oscillation.
  const auto saturating = [&](double t) { return std::clamp(growing(t), -10.0, 10.0); };
  const Oscillation s = find_oscillation(tracked(10.0, saturating).half_cycles, jc);
  REQUIRE(s.detected);
  CHECK(s.growing);  // named by how it began
  CHECK(s.amplitude_deg == Approx(10.0));
  CHECK(s.cycles >= 14);
}

TEST_CASE("tracking: a doublet's decaying response and a lightly damped ringing are not named",
          "[launcher][tracking]") {
  const JudgeConfig jc;
  // The fast gains' dominant pair (rig loop: 2.36 Hz, damping 0.069) rung at 40 deg: it stays
  // above 4 deg for about 5 cycles.
  const Oscillation nominal = find_oscillation(tracked(6.0, ringing(40.0, 2.36, 0.069)).half_cycles, jc);
  CHECK_FALSE(nominal.detected);
  // Damping 0.006 (the loop at 0.7x its delay margin) still decays: not named...
  CHECK_FALSE(find_oscillation(tracked(10.0, ringing(20.0, 2.3, 0.006)).half_cycles, jc).detected);
  // ... damping 0.001 does not, by the judge's bound (0.0025): named, as sustained.
  const Oscillation undamped = find_oscillation(tracked(10.0, ringing(20.0, 2.3, 0.001)).half_cycles, jc);
  CHECK(undamped.detected);
  CHECK_FALSE(undamped.growing);
  CHECK(undamped.damping_ratio == Approx(0.001).margin(0.0003));

  // A doublet through a well-damped loop: the reference's two pulses (35 deg, 4 Hz) and the
  // error that follows them.
  const auto reference = [](double t) { return t < 1.0 ? 0.0 : t < 1.125 ? -35.0 : t < 1.25 ? 35.0 : 0.0; };
  const auto error = [&](double t) { return t < 1.0 ? 0.0 : ringing(25.0, 2.36, 0.069)(t - 1.0); };
  const TrackingVerdict tv = judge_tracking(tracked(6.0, error, reference), jc);
  CHECK(tv.judged);
  CHECK_FALSE(tv.oscillation.detected);
  CHECK_FALSE(tv.lost);
  CHECK(tv.text.empty());
  const Verdict v = judge_run(within_limits(), jc, false, "", {}, false, "", tv);
  CHECK(v.exit_code == kRunOk);
  CHECK(v.text == "ok");
}

TEST_CASE("tracking: noise is not an oscillation, and a sine the reference drives is the manoeuvre's",
          "[launcher][tracking]") {
  const JudgeConfig jc;
  std::mt19937_64 rng(3);
  std::normal_distribution<double> noise(0.0, 0.6);  // twice hover's RMS error (0.19-0.29 deg)
  std::vector<double> samples;
  for (int k = 0; k <= 20 * 512; ++k) samples.push_back(noise(rng));
  const TrackingSummary s =
      tracked(20.0, [&](double t) { return samples[static_cast<std::size_t>(std::lround(t * kRate))]; });
  CHECK_FALSE(s.half_cycles.empty());  // it does cross the dead band
  const TrackingVerdict tv = judge_tracking(s, jc);
  CHECK_FALSE(tv.oscillation.detected);
  CHECK_FALSE(tv.lost);

  // The error of a loop that follows a 2 Hz sine reference with a lag: no oscillation of the loop's
  // own; with the reference held, the same error is one.
  const auto error = [](double t) { return 10.0 * std::sin(2.0 * M_PI * 2.0 * t); };
  const auto sweep = [](double t) { return 30.0 * std::sin(2.0 * M_PI * 2.0 * t + 1.0); };
  CHECK_FALSE(find_oscillation(tracked(6.0, error, sweep).half_cycles, jc).detected);
  CHECK(find_oscillation(tracked(6.0, error).half_cycles, jc).detected);
  JudgeConfig any_reference = jc;
  any_reference.oscillation_reference_still_deg = 180.0;
  CHECK(find_oscillation(tracked(6.0, error, sweep).half_cycles, any_reference).detected);
}

TEST_CASE("tracking: the amplitude, cycle and period bounds are the judge's", "[launcher][tracking]") {
  const auto sine = [](double t) { return 3.0 * std::sin(2.0 * M_PI * 3.0 * t); };
  JudgeConfig jc;
  CHECK_FALSE(find_oscillation(tracked(5.0, sine).half_cycles, jc).detected);  // 3 deg < 4
  jc.oscillation_amplitude_deg = 2.5;
  CHECK(find_oscillation(tracked(5.0, sine).half_cycles, jc).detected);
  // Two and a half cycles are fewer than three; with two asked, enough.
  jc = JudgeConfig{};
  const auto burst = [](double t) { return t < 2.5 / 3.0 ? 20.0 * std::sin(2.0 * M_PI * 3.0 * t) : 0.0; };
  CHECK_FALSE(find_oscillation(tracked(2.0, burst).half_cycles, jc).detected);
  jc.oscillation_cycles = 2;
  CHECK(find_oscillation(tracked(2.0, burst).half_cycles, jc).detected);
  // Cycles of 0.25 s and 0.5 s in turn: full periods 43 % off their mean, not one oscillation
  // within 20 %; within 50 %, one.
  jc = JudgeConfig{};
  const auto alternating = [](double t) {
    const double u = std::fmod(t, 0.75);
    return u < 0.25 ? 20.0 * std::sin(2.0 * M_PI * 4.0 * u) : 20.0 * std::sin(2.0 * M_PI * 2.0 * (u - 0.25));
  };
  CHECK_FALSE(find_oscillation(tracked(6.0, alternating).half_cycles, jc).detected);
  jc.oscillation_period_tolerance = 0.5;
  CHECK(find_oscillation(tracked(6.0, alternating).half_cycles, jc).detected);
  // No half-cycles, no oscillation.
  CHECK_FALSE(find_oscillation({}, jc).detected);
}

TEST_CASE("tracking: an error beyond its RMS or peak bound is lost, and a run without a controller is not judged",
          "[launcher][tracking]") {
  JudgeConfig jc;
  // A 100 deg step of the error for 0.05 s in 10 s: RMS 7 deg, peak 100 deg.
  const auto spike = [](double t) { return t >= 5.0 && t < 5.05 ? 100.0 : 0.0; };
  const TrackingVerdict peak = judge_tracking(tracked(10.0, spike), jc);
  CHECK(peak.lost);
  CHECK_FALSE(peak.oscillation.detected);
  CHECK(peak.max_deg == Approx(100.0));
  CHECK(peak.max_at_s == Approx(5.0));
  CHECK(peak.text == "roll tracking error 100.0 deg at t = 5.00 s (limit 90 deg)");
  jc.max_tracking_error_deg = 105.0;
  CHECK_FALSE(judge_tracking(tracked(10.0, spike), jc).lost);
  const auto offset = [](double) { return 21.0; };  // a steady error: no half-cycle ends
  const TrackingVerdict rms = judge_tracking(tracked(10.0, offset), JudgeConfig{});
  CHECK(rms.lost);
  CHECK(rms.text == "roll tracking error rms 21.0 deg (limit 20 deg)");
  jc.max_tracking_rms_deg = 25.0;
  CHECK_FALSE(judge_tracking(tracked(10.0, offset), jc).lost);

  const TrackingVerdict none = judge_tracking(TrackingSummary{}, JudgeConfig{});
  CHECK_FALSE(none.judged);
  CHECK_FALSE(none.lost);
  CHECK(judge_run(within_limits(), JudgeConfig{}, false, "", {}, false, "", none).exit_code == kRunOk);
}

TEST_CASE("tracking: beyond the limits the run is not controlled and names its oscillation, and failures outrank it",
          "[launcher][tracking]") {
  const JudgeConfig jc;
  const TrackingVerdict tv = judge_tracking(tracked(6.0, ringing(60.0, 2.0, 0.0)), jc);
  REQUIRE(tv.lost);
  FlightSummary beyond = within_limits();
  beyond.max_abs_phi = 85.0 * M_PI / 180.0;
  const Verdict v = judge_run(beyond, jc, false, "", {}, false, "", tv);
  CHECK(v.exit_code == kRunNotControlled);
  CHECK(v.text == "completed, vehicle NOT controlled (roll oscillation 2.0 Hz +-60 deg sustained from t = 0.0 s)");
  CHECK(judge_run(within_limits(), jc, false, "plant died", {}, false, "", tv).exit_code == kRunFailed);
  CHECK(judge_run(within_limits(), jc, false, "", {}, false, "controller: failsafe", tv).exit_code == kRunFailsafe);
  TimingVerdict degraded;
  degraded.degraded = true;
  degraded.text = "real-time degraded: ...";
  CHECK(judge_run(within_limits(), jc, false, "", degraded, true, "", tv).exit_code == kRunNotTracking);
}

TEST_CASE("tracking: the report's text and JSON carry the tracking figures and the oscillation",
          "[launcher][tracking]") {
  RunReport r;
  r.scenario = "unit";
  r.clock = kClockInprocess;
  r.flight = within_limits();
  r.tracking = tracked(6.0, [](double t) { return 30.0 * std::sin(2.0 * M_PI * 4.0 * t); });
  r.verdict = judge_run(r.flight, JudgeConfig{}, false, "", {}, false, "", judge_tracking(r.tracking, JudgeConfig{}));
  std::ostringstream text;
  write_report_text(text, r);
  CHECK(text.str().find("tracking   roll error rms 21.21 deg, max 30.00 deg") != std::string::npos);
  CHECK(text.str().find("roll oscillation 4.0 Hz +-30 deg sustained from t = 0.0 s (damping ratio") !=
        std::string::npos);
  CHECK(text.str().find("result     completed, roll oscillation 4.0 Hz") != std::string::npos);
  const YAML::Node j = YAML::Load(report_json(r));
  CHECK(j["exit_code"].as<int>() == kRunNotTracking);
  const YAML::Node t = j["tracking"];
  REQUIRE(t);
  CHECK(t["samples"].as<int>() == 3073);
  CHECK(t["rms_deg"].as<double>() == Approx(21.21).epsilon(0.001));
  CHECK(t["max_deg"].as<double>() == Approx(30.0).epsilon(0.001));
  CHECK(t["lost"].as<bool>());
  CHECK(t["oscillation"]["detected"].as<bool>());
  CHECK(t["oscillation"]["kind"].as<std::string>() == "sustained");
  CHECK(t["oscillation"]["frequency_hz"].as<double>() == Approx(4.0).epsilon(0.01));
  CHECK(t["oscillation"]["amplitude_deg"].as<double>() == Approx(30.0).epsilon(0.01));
  CHECK(t["oscillation"]["start_s"].as<double>() == Approx(0.0).margin(0.01));
  CHECK(t["oscillation"]["cycles"].as<int>() == 23);
  // Without a controller there is nothing to write.
  r.tracking = TrackingSummary{};
  CHECK_FALSE(YAML::Load(report_json(r))["tracking"]);
}
