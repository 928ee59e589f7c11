// Functional tests of the rig-log reader (ident/rig_log.h) on LCM logs written here:
// every sample lands at the instant it describes.

#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iterator>
#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nimble/actuator_feedback_t.hpp>
#include <nimble/estimator_state_t.hpp>
#include <nimble/imu_sample_t.hpp>
#include <nimble/mocap_pose_t.hpp>
#include <nimble/truth_state_t.hpp>

#include "contract/channels.h"
#include "core/attitude.h"
#include "lcmlog/lcm_log.h"
#include "ident/rig_log.h"
#include "ident/signal.h"
#include "../support/run_rig.h"
#include "tests/support/scratch.h"

using namespace nimble;
using namespace nimble::ident;
using nimble::lcmlog::LcmLogReader;
using nimble::lcmlog::LogEventRecord;
using namespace nimble::contract::channels;

namespace {

std::string temp_log(const std::string& name) { return nimble::test::scratch_file("test_rig_log", name); }

template <typename T>
void write(lcm::LogFile& log, const std::string& channel, const T& msg, int64_t utime) {
  std::vector<uint8_t> buf(static_cast<std::size_t>(msg.getEncodedSize()));
  REQUIRE(msg.encode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
  lcm::LogEvent ev{};
  ev.timestamp = utime;
  ev.channel = channel;
  ev.datalen = static_cast<int32_t>(buf.size());
  ev.data = buf.data();
  REQUIRE(log.writeEvent(&ev) == 0);
}

/// Roll rate, sideslip velocity and roll angle of the test flight at time t [s].
double p_of(double t) { return std::sin(2.0 * M_PI * 3.0 * t); }
double v_of(double t) { return 0.2 * std::cos(2.0 * M_PI * 1.0 * t); }
double phi_of(double t) { return -std::cos(2.0 * M_PI * 3.0 * t) / (2.0 * M_PI * 3.0); }

/// The timing of a lockstep rig log: TRUTH at 1 kHz, IMU samples at the plant steps
/// nearest 512 Hz (every 1 or 2 ms), the estimator publishing at its 512 Hz ticks the
/// state at the newest IMU sample before the tick, actuator feedback at 100 Hz.
struct LockstepLog {
  std::vector<int64_t> imu_utimes;  ///< imu_utime of each ESTIMATE written
  std::vector<int64_t> utimes;      ///< utime of each ESTIMATE written
};

LockstepLog write_lockstep_log(const std::string& file, double duration_s) {
  lcm::LogFile log(file, "w");
  REQUIRE(log.good());
  const int64_t end_us = static_cast<int64_t>(duration_s * 1e6);
  for (int64_t us = 0; us <= end_us; us += 1000) {
    const double t = static_cast<double>(us) * 1e-6;
    truth_state_t tr{};
    tr.utime = us;
    tr.omega_body_radps[0] = p_of(t);
    tr.velocity_body_mps[1] = v_of(t);
    tr.euler_rad[0] = phi_of(t);
    write(log, kTruth, tr, us);
  }
  // IMU samples at the first plant step at or after each 512 Hz instant.
  std::vector<int64_t> imu;
  for (int k = 0; static_cast<double>(k) * 1953.125 <= static_cast<double>(end_us); ++k) {
    imu.push_back(static_cast<int64_t>(std::ceil(static_cast<double>(k) * 1953.125 / 1000.0)) * 1000);
  }
  // Estimator ticks at 512 Hz (whole microseconds), each publishing the state at the
  // newest IMU sample before the tick.
  LockstepLog out;
  for (int k = 1; static_cast<double>(k) * 1953.125 <= static_cast<double>(end_us); ++k) {
    const int64_t tick = static_cast<int64_t>(std::floor(static_cast<double>(k) * 1953.125));
    int64_t newest = -1;
    for (const int64_t s : imu) {
      if (s < tick) newest = s;
    }
    estimator_state_t e{};
    e.utime = tick;
    e.imu_utime = newest;
    const double ti = static_cast<double>(newest) * 1e-6;
    e.omega_body_radps[0] = p_of(ti);
    e.velocity_body_mps[1] = v_of(ti);
    e.euler_rad[0] = phi_of(ti);
    write(log, kEstimate, e, tick);
    out.utimes.push_back(tick);
    out.imu_utimes.push_back(newest);
  }
  for (int64_t us = 0; us <= end_us; us += 10000) {
    actuator_feedback_t fb{};
    fb.utime = us;
    fb.delta_f_radps = 40.0 * p_of(static_cast<double>(us) * 1e-6);
    write(log, kActuatorFeedback, fb, us);
  }
  return out;
}

}  // namespace

TEST_CASE("ESTIMATE states are placed at the IMU sample they describe, not at their publication", "[rig_log]") {
  const std::string file = temp_log("lockstep.lcmlog");
  const LockstepLog written = write_lockstep_log(file, 1.0);
  REQUIRE(written.utimes.size() > 500);
  // The log has the lockstep offset: published 1-2 ms after the IMU sample.
  double mean_offset_us = 0.0;
  for (std::size_t i = 0; i < written.utimes.size(); ++i) {
    const int64_t d = written.utimes[i] - written.imu_utimes[i];
    REQUIRE(d > 0);
    REQUIRE(d <= 2000);
    mean_offset_us += static_cast<double>(d) / static_cast<double>(written.utimes.size());
  }
  CHECK(mean_offset_us > 900.0);

  const RigLogData d = read_rig_log(file);
  CHECK(d.state_source == "estimate");
  const Channel& p = d.measured.channels.at("p");
  REQUIRE(p.t_s.size() == written.imu_utimes.size());
  for (std::size_t i = 0; i < p.t_s.size(); ++i) {
    CHECK(p.t_s[i] == static_cast<double>(written.imu_utimes[i]) * 1e-6);
    CHECK(p.values[i] == p_of(p.t_s[i]));
  }
  // Resampled, the estimated states equal the truth up to interpolation error; stamped at
  // publication they would be late by the mean offset (p error ~ 2 pi 3 Hz x 1.5 ms ~ 3 %).
  const UniformData est = resample_uniform(d.measured, 512.0);
  double worst = 0.0;
  for (Eigen::Index k = 0; k < est.size(); ++k) {
    worst = std::max(worst, std::fabs(est.at("p")[k] - p_of(est.t_s[k])));
    CHECK(est.at("v")[k] == Approx(v_of(est.t_s[k])).margin(1e-5));
    CHECK(est.at("phi")[k] == Approx(phi_of(est.t_s[k])).margin(1e-5));
  }
  INFO("worst p error after resampling " << worst);
  CHECK(worst < 2e-3);
  CHECK(d.truth.has("p"));
  CHECK(read_rig_log(file, StateSource::kTruth).state_source == "truth");
}

TEST_CASE("estimate_time_s: imu_utime when it is valid, else the publication time", "[rig_log]") {
  CHECK(estimate_time_s(11718, 10000) == 10000e-6);
  CHECK(estimate_time_s(10000, 10000) == 10000e-6);
  CHECK(estimate_time_s(11718, 0) == 0.0);
  CHECK(estimate_time_s(11718, 12000) == 11718e-6);  // an IMU sample after the publication: not trusted
  CHECK(estimate_time_s(11718, -1) == 11718e-6);
}

TEST_CASE("a repeated estimate time keeps the newest estimate of that instant", "[rig_log]") {
  const std::string file = temp_log("repeat.lcmlog");
  {
    lcm::LogFile log(file, "w");
    REQUIRE(log.good());
    for (int k = 0; k < 4; ++k) {
      estimator_state_t e{};
      e.utime = 2000 * k + 1500;
      e.imu_utime = 2000 * k;
      e.omega_body_radps[0] = k;
      write(log, kEstimate, e, e.utime);
      if (k == 1) {  // a pose update of the same instant, published again
        e.utime += 300;
        e.omega_body_radps[0] = 10.0;
        write(log, kEstimate, e, e.utime);
      }
      actuator_feedback_t fb{};
      fb.utime = 2000 * k;
      write(log, kActuatorFeedback, fb, fb.utime);
    }
  }
  const RigLogData d = read_rig_log(file, StateSource::kEstimate);
  const Channel& p = d.measured.channels.at("p");
  CHECK(p.t_s == std::vector<double>{0.0, 2000e-6, 4000e-6, 6000e-6});
  CHECK(p.values == std::vector<double>{0.0, 10.0, 2.0, 3.0});
  CHECK_FALSE(d.truth.has("p"));
}

namespace {

std::vector<char> file_bytes(const std::string& file) {
  std::ifstream in(file, std::ios::binary);
  return std::vector<char>(std::istreambuf_iterator<char>(in), {});
}

void put_bytes(const std::string& file, const std::vector<char>& bytes) {
  std::ofstream out(file, std::ios::binary | std::ios::trunc);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

/// The byte offset of each event of a whole log, by reading it.
std::vector<int64_t> event_offsets(const std::string& file) {
  LcmLogReader reader(file);
  std::vector<int64_t> offsets;
  LogEventRecord ev;
  while (reader.next(&ev)) offsets.push_back(ev.offset);
  return offsets;
}

std::string what_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const DataError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("a damaged log is refused naming the byte offset and the event, --salvage reads what precedes it",
          "[ident]") {
  const std::string whole = temp_log("whole.lcmlog");
  write_lockstep_log(whole, 1.0);
  const std::vector<char> bytes = file_bytes(whole);
  const std::vector<int64_t> offsets = event_offsets(whole);
  REQUIRE(offsets.size() > 1000);
  const RigLogData full = read_rig_log(whole);
  CHECK(full.damage.empty());

  // Cut in the middle of an event (half the file): an error, not half a flight.
  const std::size_t k = offsets.size() / 2;
  const std::string cut = temp_log("cut.lcmlog");
  put_bytes(cut, std::vector<char>(bytes.begin(), bytes.begin() + offsets[k] + 30));
  const std::string message = what_of([&] { read_rig_log(cut); });
  INFO(message);
  CHECK(message.find(cut) != std::string::npos);
  CHECK(message.find("damaged at byte " + std::to_string(offsets[k])) != std::string::npos);
  CHECK(message.find("event " + std::to_string(k + 1) + " (after " + std::to_string(k) + " whole events)") !=
        std::string::npos);
  CHECK(message.find("truncated") != std::string::npos);
  // Salvaged: exactly the whole events before the cut, and how much was left.
  LogReadOptions salvage;
  salvage.salvage = true;
  LcmLogReader reader(cut, true);
  LogEventRecord ev;
  std::size_t read = 0;
  while (reader.next(&ev)) ++read;
  CHECK(read == k);
  CHECK(reader.damage().find("read the " + std::to_string(k) + " events before it, left 30 bytes") !=
        std::string::npos);
  // (this test log writes its channels one after the other: the half before the cut has no
  // actuator feedback, which read_rig_log names rather than returning states without inputs)
  CHECK(what_of([&] { read_rig_log(cut, StateSource::kAuto, salvage); }).find("no actuator feedback") !=
        std::string::npos);

  // Corrupted in the middle (the sync word of event k overwritten): refused at that event.
  std::vector<char> corrupt = bytes;
  corrupt[static_cast<std::size_t>(offsets[k])] ^= 0x5a;
  const std::string corrupted = temp_log("corrupt.lcmlog");
  put_bytes(corrupted, corrupt);
  const std::string bad_sync = what_of([&] { read_rig_log(corrupted); });
  CHECK(bad_sync.find("damaged at byte " + std::to_string(offsets[k])) != std::string::npos);
  CHECK(bad_sync.find("no event sync word") != std::string::npos);
  // An impossible data length (the event would run past the end).
  std::vector<char> long_event = bytes;
  long_event[static_cast<std::size_t>(offsets[k]) + 24] = 0x7f;
  put_bytes(corrupted, long_event);
  CHECK(what_of([&] { read_rig_log(corrupted); }).find("damaged at byte " + std::to_string(offsets[k])) !=
        std::string::npos);
  // Not a log at all.
  put_bytes(corrupted, std::vector<char>{'t', ',', 'p', '\n'});
  CHECK(what_of([&] { LcmLogReader r(corrupted); }).find("is not an LCM log") != std::string::npos);
}

TEST_CASE(
    "rig export --csv of a log with one damaged payload names what it left out, by channel and count, on "
    "stderr and in --json, as the MCAP export does",
    "[ident][bad_data]") {
  // One second of TRUTH (1 kHz) and ACTUATOR_FB (100 Hz); at 0.5 s a motion-capture pose whose
  // payload is damaged (its fingerprint, the event's framing intact), as a fault test's garbage
  // or a bad sector would leave it. The CSV does not use MOCAP_POSE, so it used to pass over it
  // without a word.
  const std::string log = temp_log("one_damaged.lcmlog");
  {
    lcm::LogFile out(log, "w");
    REQUIRE(out.good());
    for (int64_t us = 0; us <= 1000000; us += 1000) {
      truth_state_t tr{};
      tr.utime = us;
      tr.omega_body_radps[0] = p_of(static_cast<double>(us) * 1e-6);
      write(out, kTruth, tr, us);
      if (us % 10000 == 0) {
        actuator_feedback_t fb{};
        fb.utime = us;
        write(out, kActuatorFeedback, fb, us);
      }
      if (us == 500000) {
        mocap_pose_t pose{};
        pose.utime = us;
        pose.quaternion_wxyz[0] = 1.0;
        std::vector<uint8_t> buf(static_cast<std::size_t>(pose.getEncodedSize()));
        REQUIRE(pose.encode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
        buf[3] ^= 0xff;  // the payload's fingerprint
        lcm::LogEvent ev{};
        ev.timestamp = us;
        ev.channel = kMocapPose;
        ev.datalen = static_cast<int32_t>(buf.size());
        ev.data = buf.data();
        REQUIRE(out.writeEvent(&ev) == 0);
      }
    }
  }
  const std::string csv = temp_log("one_damaged.csv"), json = temp_log("one_damaged.json");
  const nimble::test::RigResult r = nimble::test::run_rig("export " + log + " --csv " + csv + " --json " + json);
  INFO(r.err);
  REQUIRE(r.exit_code == 0);
  CHECK(r.out.find("rig export: 513 samples at 512 Hz") != std::string::npos);
  CHECK(r.err == "rig export: warning: " + log + ": 1 undecodable left out (MOCAP_POSE 1)\n");
  const std::string j = nimble::test::slurp(json);
  CHECK(j.find("\"undecodable\":1,\"undecodable_channels\":{\"MOCAP_POSE\":1}") != std::string::npos);
  // The MCAP export of the same log says the same.
  const std::string mcap = temp_log("one_damaged.mcap"), mjson = temp_log("one_damaged_mcap.json");
  const nimble::test::RigResult m = nimble::test::run_rig("export " + log + " --out " + mcap + " --json " + mjson);
  REQUIRE(m.exit_code == 0);
  CHECK(m.out.find("; 1 undecodable left out (MOCAP_POSE 1)") != std::string::npos);
  CHECK(nimble::test::slurp(mjson).find("\"undecodable_channels\":{\"MOCAP_POSE\":1}") != std::string::npos);
}

TEST_CASE(
    "smoothed states of a rig flight: made offline from its IMU and motion capture, closer to the truth than "
    "the on-board estimate, and rig identify --states smoothed reads them",
    "[ident]") {
  const std::string log = temp_log("smoothed.lcmlog");
  const auto fly = nimble::test::run_rig("run " + std::string(RIG_SOURCE_DIR) +
                                         "/rig_configs/id_doublet_train_fast.yaml --clock inprocess --seed 3 --log " +
                                         log + " --no-progress --set duration_s=8");
  INFO(fly.out << fly.err);
  REQUIRE(fly.exit_code == 0);
  const RigLogData estimate = read_rig_log(log, StateSource::kEstimate);
  const RigLogData smoothed = read_rig_log(log, StateSource::kSmoothed);
  CHECK(smoothed.state_source == "smoothed");
  // rms error of v and phi against the truth, on the states' own instants (truth at 1 kHz, linear between).
  const auto rms = [](const Channel& x, const Channel& truth) {
    double se = 0;
    int n = 0;
    std::size_t j = 1;
    for (std::size_t i = 0; i < x.t_s.size(); ++i) {
      if (x.t_s[i] < 1.0) continue;  // after the filters' first second
      while (j < truth.t_s.size() && truth.t_s[j] < x.t_s[i]) ++j;
      if (j >= truth.t_s.size()) break;
      const double s = (x.t_s[i] - truth.t_s[j - 1]) / (truth.t_s[j] - truth.t_s[j - 1]);
      const double e = x.values[i] - ((1 - s) * truth.values[j - 1] + s * truth.values[j]);
      se += e * e;
      ++n;
    }
    return std::sqrt(se / n);
  };
  for (const char* ch : {"v", "phi"}) {
    const double e_est = rms(estimate.measured.at(ch), estimate.truth.at(ch));
    const double e_smo = rms(smoothed.measured.at(ch), smoothed.truth.at(ch));
    INFO(ch << ": estimate " << e_est << ", smoothed " << e_smo);
    CHECK(e_smo < 0.9 * e_est);
  }
  const auto id = nimble::test::run_rig("identify " + log + " --states smoothed --json -");
  INFO(id.out << id.err);
  CHECK(id.exit_code == 0);
  CHECK(id.out.find("\"Yv\"") != std::string::npos);
  // A log without the recorded sensors has nothing to smooth, and says which.
  const std::string bare = temp_log("no_mocap.lcmlog");
  write_lockstep_log(bare, 1.0);
  CHECK(what_of([&] { read_rig_log(bare, StateSource::kSmoothed); }).find("to smooth") != std::string::npos);
}

TEST_CASE("sensors: the raw channels of a rig log, p at the IMU's own stamps and phi at the motion capture's",
          "[ident]") {
  // A short flight whose IMU clock runs 30 ms ahead of the motion capture's.
  const std::string log = temp_log("sensors.lcmlog");
  const auto fly = nimble::test::run_rig("run " + std::string(RIG_SOURCE_DIR) +
                                         "/rig_configs/hover.yaml --clock inprocess --no-progress --set duration_s=1"
                                         " --set processes=[plant,controller,mocap] --set run.controller_input=truth"
                                         " --set sensing.imu.clock_offset_s=0.03"
                                         " --log " +
                                         log);
  INFO(fly.out << fly.err);
  REQUIRE(fly.exit_code == 0);
  // The log's own IMU and MOCAP_POSE messages.
  std::vector<std::pair<double, double>> imu_p, pose_phi;
  LcmLogReader reader(log, false);
  LogEventRecord ev;
  while (reader.next(&ev)) {
    if (ev.channel == kImu) {
      imu_sample_t m{};
      REQUIRE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) > 0);
      imu_p.emplace_back(1e-6 * static_cast<double>(m.utime), m.gyro_radps[0]);
    } else if (ev.channel == kMocapPose) {
      mocap_pose_t m{};
      REQUIRE(m.decode(ev.data.data(), 0, static_cast<int>(ev.data.size())) > 0);
      if (!m.tracking_valid) continue;
      const Eigen::Quaterniond q(m.quaternion_wxyz[0], m.quaternion_wxyz[1], m.quaternion_wxyz[2],
                                 m.quaternion_wxyz[3]);
      pose_phi.emplace_back(1e-6 * static_cast<double>(m.utime), euler_zyx_from_rotation(q.toRotationMatrix())[0]);
    }
  }
  REQUIRE(imu_p.size() > 500);
  REQUIRE(pose_phi.size() > 190);
  const RigLogData d = read_rig_log(log, StateSource::kSensors);
  CHECK(d.state_source == "sensors");
  const Channel& p = d.measured.at("p");
  const Channel& phi = d.measured.at("phi");
  // p: every IMU message's gyro at its own stamp, which runs 30 ms ahead of the rig time.
  REQUIRE(p.t_s.size() == imu_p.size());
  for (std::size_t i = 0; i < p.t_s.size(); ++i) {
    REQUIRE(p.t_s[i] == imu_p[i].first);
    REQUIRE(p.values[i] == imu_p[i].second);
  }
  CHECK(p.t_s.front() == Approx(0.030).margin(1e-9));  // the first sample, taken at rig time 0
  // phi: every tracked frame's attitude at its mid-exposure stamp, untouched by the IMU's clock.
  REQUIRE(phi.t_s.size() == pose_phi.size());
  for (std::size_t i = 0; i < phi.t_s.size(); ++i) {
    REQUIRE(phi.t_s[i] == pose_phi[i].first);
    REQUIRE(phi.values[i] == Approx(pose_phi[i].second).margin(1e-12));
  }
  CHECK(phi.t_s.front() < 0.01);
  CHECK(d.measured.has("u"));  // the differentiated positions
  CHECK(d.measured.has("ax"));
  CHECK(d.measured.origin.at("p").first == kImu);
  CHECK(d.measured.origin.at("phi").first == kMocapPose);
  // A log without motion capture has no attitude to give, and says so.
  const std::string bare = temp_log("sensors_no_mocap.lcmlog");
  write_lockstep_log(bare, 1.0);
  CHECK(what_of([&] { read_rig_log(bare, StateSource::kSensors); }).find("no IMU samples") != std::string::npos);
  CHECK(state_source_from_name("sensors") == StateSource::kSensors);
}
