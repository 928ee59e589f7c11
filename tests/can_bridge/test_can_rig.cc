// The CAN actuator link of the rig on a real SocketCAN interface (vcan0), run by
// tools/canvm/canvm ctest-wrap (in a qemu VM on kernels without CAN, else in a private
// network namespace). One executable = one VM boot.
//
//  - the bridge node itself, in this process on LCM's memq://: LCM messages become the
//    documented frames, frames sent with cansend become LCM messages, and bad frames and
//    error frames are counted, reported and dropped;
//  - the real processes through `rig run`: the identification doublet train in lockstep
//    gives the same truth over the CAN link as over LCM, the summary reports both sides'
//    health, and the run's candump log replays with canplayer.
//  - CAN FD (can_bridge.fd: true) on vcan1, which the FD cases create with MTU 72: the bridge
//    node's frames are FD frames with bit rate switch, FD frames from cansend are decoded, and a
//    short lockstep `rig run` carries every command across in FD frames.

#include <linux/can/error.h>
#include <net/if.h>
#include <sys/ioctl.h>
#include <sys/socket.h>
#include <sched.h>
#include <sys/wait.h>
#include <unistd.h>

#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <thread>
#include <vector>

#include <catch2/catch.hpp>
#include <lcm/lcm-cpp.hpp>
#include <nimble/can_health_t.hpp>
#include <nimble/fault_event_t.hpp>
#include <nimble/truth_state_t.hpp>
#include <yaml-cpp/yaml.h>

#include "can_bridge/bridge_node.h"
#include "can_bridge/candump_log.h"
#include "can_bridge/codec.h"
#include "contract/channels.h"
#include "can_bridge/frame_layout.h"
#include "launcher/netns.h"

#include "../support/rig_runs.h"

using namespace nimble::can;
using nimble::actuator_command_t;
using nimble::actuator_feedback_t;
using nimble::can_health_t;
using nimble::fault_event_t;
using namespace nimble::contract::channels;
namespace fs = std::filesystem;
using nimble::test::differing;
using nimble::test::rig_run;
using nimble::test::RunResult;
using nimble::test::truth_payloads;

namespace {

const std::string kIf = "vcan0";
const std::string kConfigs = std::string(RIG_SOURCE_DIR) + "/rig_configs/";

int run(const std::string& cmd) {
  INFO(cmd);
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

std::string hex(const can_frame& f, int len = -1) {
  std::string s;
  char b[3];
  const int n = len < 0 ? f.len : len;
  for (int i = 0; i < n; ++i) {
    std::snprintf(b, sizeof b, "%02X", f.data[i]);
    s += b;
  }
  return s;
}

/// `cansend IF ID#DATA` for a frame (first `len` data bytes; all if negative).
std::string cansend(const can_frame& f, int len = -1, const std::string& interface = kIf) {
  char id[8];
  std::snprintf(id, sizeof id, "%03X", f.can_id & CAN_SFF_MASK);
  return "cansend " + interface + " " + id + "#" + hex(f, len);
}

/// The CAN FD interface (MTU 72) of the FD cases; vcan0 keeps the classical MTU.
const std::string kFdIf = "vcan1";

void ensure_fd_interface() {
  if (::if_nametoindex(kFdIf.c_str()) != 0) return;
  // A vcan's MTU can only be changed while it is down, as it is after `ip link add`.
  REQUIRE(run("ip link add dev " + kFdIf + " type vcan && ip link set " + kFdIf + " mtu 72 && ip link set " + kFdIf +
              " up") == 0);
}

/// `cansend vcan1 ID##1DATA` for a frame: an FD frame with bit rate switch.
std::string cansend_fd(const can_frame& f, const std::string& data) {
  char id[8];
  std::snprintf(id, sizeof id, "%03X", f.can_id & CAN_SFF_MASK);
  return "cansend " + kFdIf + " " + id + "##1" + data;
}

CanSocketOptions receive_all() {
  CanSocketOptions o;
  o.receive_all = true;
  o.error_frames = false;
  return o;
}

/// A socket on the FD interface that receives every frame, classical and FD.
CanSocket fd_listener() {
  CanSocketOptions o = receive_all();
  o.fd = true;
  return CanSocket::open(kFdIf, o);
}

bool same_frame(const can_frame& a, const can_frame& b) {
  return a.can_id == b.can_id && a.len == b.len && std::memcmp(a.data, b.data, a.len) == 0;
}

/// Keeps this test and everything it starts (cansend, rig run) on CPU 0. vcan hands a frame
/// to the receive path of the CPU that sent it; frames sent one after the other from two
/// CPUs (two cansend processes, or a process that migrates) can then arrive out of order,
/// and the bridge would rightly drop the older one as stale. A CAN controller keeps the
/// order of the wire; on vcan one CPU does.
void pin_to_cpu0() {
  cpu_set_t cpu0;
  CPU_ZERO(&cpu0);
  CPU_SET(0, &cpu0);
  REQUIRE(::sched_setaffinity(0, sizeof cpu0, &cpu0) == 0);
}

/// A bridge node of one side on memq://, with the messages it publishes collected.
struct Bridge {
  explicit Bridge(const std::string& side, bool fd = false)
      : pinned((pin_to_cpu0(), true)),
        scenario(
            nimble::load_scenario(kConfigs + "id_doublet_train_fast.yaml", {{"actuator_link", "can"},
                                                                            {"can_bridge.interface", fd ? kFdIf : kIf},
                                                                            {"can_bridge.fd", fd ? "true" : "false"}})),
        node(scenario, {side, scenario.file, "memq://"}) {
    auto& bus = node.node().bus();
    bus.subscribe<actuator_command_t>(kActuatorCommandCan,
                                      [this](const actuator_command_t& m) { commands.push_back(m); });
    bus.subscribe<actuator_feedback_t>(kActuatorFeedbackCan,
                                       [this](const actuator_feedback_t& m) { feedback.push_back(m); });
    bus.subscribe<can_health_t>(kCanHealth, [this](const can_health_t& m) { health.push_back(m); });
    bus.subscribe<fault_event_t>(kFault, [this](const fault_event_t& m) { faults.push_back(m); });
  }
  /// Hands the node every frame waiting on vcan0, then delivers what it published.
  void pump() {
    node.drain_socket();
    node.publish_health();
    while (node.node().bus().handle_timeout(0) > 0) {
    }
  }
  bool fault_mentions(const std::string& text) const {
    for (const auto& f : faults) {
      if (f.message.find(text) != std::string::npos) return true;
    }
    return false;
  }
  bool pinned;
  nimble::Scenario scenario;
  CanBridgeNode node;
  std::vector<actuator_command_t> commands;
  std::vector<actuator_feedback_t> feedback;
  std::vector<can_health_t> health;
  std::vector<fault_event_t> faults;
};

actuator_command_t sample_command(int64_t seq) {
  actuator_command_t c{};
  c.seq = seq;
  c.mode = actuator_command_t::MODE_LEFT_RIGHT;
  c.flap_freq_left_radps = 131.25;
  c.flap_freq_right_radps = 88.5;
  c.delta_f_radps = c.flap_freq_left_radps - c.flap_freq_right_radps;
  c.flap_freq_collective_radps = 0.5 * (c.flap_freq_left_radps + c.flap_freq_right_radps);
  c.throttle_pct = 62.5;
  c.dihedral_rad = -0.1234;
  c.wing_root_rad = 0.0567;
  c.rolling_counter = static_cast<int8_t>(seq % 16);
  c.input_utime = 777;
  c.source = "controller";
  return c;
}

/// sample_command(seq) as the rig side publishes it after the frames (frame resolution).
void check_sample_command(const actuator_command_t& c, int64_t seq) {
  CHECK(c.seq == seq);
  CHECK(c.flap_freq_left_radps == Approx(131.25).margin(0.005));
  CHECK(c.flap_freq_right_radps == Approx(88.5).margin(0.005));
  CHECK(c.delta_f_radps == Approx(131.25 - 88.5).margin(0.01));
  CHECK(c.dihedral_rad == Approx(-0.1234).margin(5e-5));
  CHECK(c.wing_root_rad == Approx(0.0567).margin(5e-5));
  CHECK(c.throttle_pct == Approx(62.5).margin(0.005));
  CHECK(c.source == kRigProcess);
  CHECK(c.input_utime == -1);  // the frames do not carry it
}

/// Feedback as a motor controller reports it (sent with cansend to the flight side).
actuator_feedback_t motor_feedback(int64_t cmd_seq) {
  actuator_feedback_t fb{};
  fb.flap_freq_left_radps = 110.37;
  fb.flap_freq_right_radps = 95.02;
  fb.dihedral_rad = 0.0421;
  fb.wing_root_rad = -0.0033;
  fb.throttle_pct = -2.5;
  fb.cmd_seq = cmd_seq;
  fb.cmd_age_us = 1500;
  fb.safe_state = false;
  return fb;
}

/// motor_feedback(cmd_seq) as the flight side publishes it after the frames.
void check_motor_feedback(const actuator_feedback_t& got, int64_t cmd_seq) {
  CHECK(got.flap_freq_left_radps == Approx(110.37).margin(0.005));
  CHECK(got.flap_freq_right_radps == Approx(95.02).margin(0.005));
  CHECK(got.delta_f_radps == Approx(110.37 - 95.02).margin(0.01));
  CHECK(got.dihedral_rad == Approx(0.0421).margin(5e-5));
  CHECK(got.wing_root_rad == Approx(-0.0033).margin(5e-5));
  CHECK(got.throttle_pct == Approx(-2.5).margin(0.005));
  CHECK(got.cmd_seq == cmd_seq);
  CHECK(got.cmd_age_us == 1500);
  CHECK_FALSE(got.safe_state);
}

/// Feedback as the plant publishes it (sent as frames by the rig side).
actuator_feedback_t plant_feedback(int64_t cmd_seq) {
  actuator_feedback_t fb{};
  fb.utime = 123456;
  fb.flap_freq_left_radps = 101.0;
  fb.flap_freq_right_radps = 103.5;
  fb.throttle_pct = 1.25;
  fb.cmd_seq = cmd_seq;
  fb.cmd_age_us = 900;
  fb.safe_state = true;
  return fb;
}

/// One shell command that sends `frames` one after the other, each made by `send`.
template <typename Frames, typename Send>
std::string send_all(const Frames& frames, Send send) {
  std::string cmd;
  for (const can_frame& f : frames) cmd += (cmd.empty() ? "" : " && ") + send(f);
  return cmd;
}

/// The next frames on `listener` are `expected`, bit for bit; with `fd`, as FD frames of 8
/// bytes with bit rate switch.
template <typename Frames>
void expect_frames(CanSocket& listener, const Frames& expected, bool fd) {
  for (const can_frame& want : expected) {
    ReceivedFrame rx;
    REQUIRE(listener.receive(&rx, 2000) == ReceiveResult::kFrame);
    INFO("frame 0x" << std::hex << rx.frame.can_id);
    if (fd) {
      REQUIRE(rx.is_fd);
      CHECK(rx.fd_frame.len == 8);
      CHECK((rx.fd_flags & CANFD_BRS) != 0);
      CHECK((rx.fd_flags & CANFD_ESI) == 0);
    }
    CHECK(same_frame(rx.frame, want));  // the documented 8-byte frame
  }
}

}  // namespace

TEST_CASE("can_flight: ACTUATOR_CMD goes out as the documented frames, feedback frames become ACTUATOR_FB_CAN",
          "[bridge]") {
  Bridge flight(kFlightProcess);
  CanSocket listener = CanSocket::open(kIf, receive_all());

  const actuator_command_t cmd = sample_command(41);
  flight.node.node().bus().publish(kActuatorCommand, cmd);
  REQUIRE(flight.node.node().bus().handle_timeout(1000) > 0);
  CommandEncoder reference;
  expect_frames(listener, reference.encode(cmd), false);

  // Feedback frames as a motor controller would send them, with cansend.
  FeedbackEncoder fenc;
  REQUIRE(run(send_all(fenc.encode(motor_feedback(41)), [](const can_frame& f) { return cansend(f); })) == 0);
  flight.pump();
  REQUIRE(flight.feedback.size() == 1);
  check_motor_feedback(flight.feedback.front(), 41);

  REQUIRE_FALSE(flight.health.empty());
  const can_health_t& h = flight.health.back();
  CHECK(h.process == kFlightProcess);
  CHECK(h.role == can_health_t::ROLE_FLIGHT);
  CHECK(h.interface_name == kIf);
  CHECK(h.messages_to_can == 1);
  CHECK(h.messages_to_lcm == 1);
  CHECK(h.frames_sent == 2);
  CHECK(h.frames_received == 3);
}

TEST_CASE("can_rig: command frames from cansend become ACTUATOR_CMD_CAN, ACTUATOR_FB goes out as frames", "[bridge]") {
  Bridge rig(kRigProcess);
  CommandEncoder enc;
  for (int64_t seq : {1000, 1001}) {
    REQUIRE(run(send_all(enc.encode(sample_command(seq)), [](const can_frame& f) { return cansend(f); })) == 0);
  }
  rig.pump();
  REQUIRE(rig.commands.size() == 2);
  check_sample_command(rig.commands.back(), 1001);

  CanSocket listener = CanSocket::open(kIf, receive_all());  // from here on: the bridge's frames only
  const actuator_feedback_t fb = plant_feedback(1001);
  rig.node.node().bus().publish(kActuatorFeedback, fb);
  REQUIRE(rig.node.node().bus().handle_timeout(1000) > 0);
  FeedbackEncoder reference;
  expect_frames(listener, reference.encode(fb), false);
  rig.pump();
  const can_health_t& h = rig.health.back();
  CHECK(h.role == can_health_t::ROLE_RIG);
  CHECK(h.messages_to_lcm == 2);
  CHECK(h.messages_to_can == 1);
  CHECK(h.frames_received == 4);
  CHECK(h.frames_sent == 3);
}

TEST_CASE("bad frames and error frames are counted, reported on CAN_HEALTH and FAULT, and dropped", "[bridge]") {
  Bridge rig(kRigProcess);
  CommandEncoder enc;
  const auto good = enc.encode(sample_command(7));
  can_frame corrupt = good[0];
  corrupt.data[0] ^= 0x01;  // payload changed, checksum kept
  std::vector<std::string> sends = {
      "cansend " + kIf + " 1FF#0011223344556677",  // unknown identifier in the rig's block
      "cansend " + kIf + " 2A0#0011223344556677",  // another node's frame: filtered by the kernel
      "cansend " + kIf + " 00000101#0011",         // extended identifier: filtered as well
      cansend(good[0], 5),                         // short frame (DLC 5)
      cansend(corrupt),                            // bad checksum
      cansend(good[0]),
      cansend(good[1]),  // a valid command
      cansend(good[1]),  // the same counter again: stale
  };
  std::string all;
  for (const auto& s : sends) all += (all.empty() ? "" : " && ") + s;
  REQUIRE(run(all) == 0);

  // An error frame, as a controller's driver reports bus-off, written through the kernel.
  CanSocketOptions tx_opts;
  tx_opts.filters.clear();
  tx_opts.error_frames = false;
  CanSocket tx = CanSocket::open(kIf, tx_opts);
  can_frame err{};
  err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF;
  err.len = CAN_ERR_DLC;
  REQUIRE(tx.send(err) == SendResult::kSent);

  rig.pump();
  REQUIRE(rig.commands.size() == 1);
  CHECK(rig.commands.front().seq == 7);
  const can_health_t& h = rig.health.back();
  CHECK(h.rejected_unknown_id == 1);
  CHECK(h.frames_received == 6);  // the block's frames only
  CHECK(h.rejected_wrong_length == 1);
  CHECK(h.rejected_bad_checksum == 1);
  CHECK(h.rejected_stale_counter == 1);
  CHECK(h.error_frames == 1);
  CHECK(h.bus_state == can_health_t::BUS_OFF);
  CHECK(h.last_error.find("bus-off") != std::string::npos);
  CHECK(rig.fault_mentions("unknown_id"));
  CHECK(rig.fault_mentions("wrong_length"));
  CHECK(rig.fault_mentions("bad_checksum"));
  CHECK(rig.fault_mentions("stale_counter"));
  CHECK(rig.fault_mentions("error frame on vcan0"));

  // The bridge goes on: the next valid command still arrives.
  const auto next = enc.encode(sample_command(8));
  REQUIRE(run(cansend(next[0]) + " && " + cansend(next[1])) == 0);
  rig.pump();
  REQUIRE(rig.commands.size() == 2);
  CHECK(rig.commands.back().seq == 8);
}

namespace {

/// A run's summary shows that all `commands` crossed the CAN link (two frames each), the
/// feedback came back, neither side rejected, dropped or saw an error frame, and every frame
/// was a CAN FD frame (`fd`) or none was.
void check_link_carried(const YAML::Node& summary, int commands, bool fd) {
  const YAML::Node ch = summary["channels"];
  CHECK(ch[kActuatorCommand]["count"].as<int>() == commands);
  CHECK(ch[kActuatorCommandCan]["count"].as<int>() == commands);
  CHECK(ch[kActuatorCommandCan]["drops"].as<int>() == 0);
  // Every feedback message crosses; nobody waits for feedback in lockstep, so the one of the very
  // last step may still be on its way when the run stops (seen under a loaded host).
  const int feedback = ch[kActuatorFeedback]["count"].as<int>();
  CHECK(ch[kActuatorFeedbackCan]["count"].as<int>() >= feedback - 1);
  CHECK(ch[kActuatorFeedbackCan]["count"].as<int>() <= feedback);
  const YAML::Node flight = summary["can"]["can_flight"], rig = summary["can"]["can_rig"];
  REQUIRE(flight);
  REQUIRE(rig);
  CHECK(flight["frames_sent"].as<int>() == 2 * commands);
  CHECK(rig["frames_received"].as<int>() == 2 * commands);
  CHECK(rig["messages_to_lcm"].as<int>() == commands);
  for (const YAML::Node& side : {flight, rig}) {
    CHECK(side["fd"].as<bool>() == fd);
    CHECK(side["fd_frames_sent"].as<int>() == (fd ? side["frames_sent"].as<int>() : 0));
    CHECK(side["fd_frames_received"].as<int>() == (fd ? side["frames_received"].as<int>() : 0));
    for (const char* key : {"rejected_unknown_id", "rejected_wrong_length", "rejected_bad_checksum",
                            "rejected_stale_counter", "rejected_out_of_range", "error_frames", "send_dropped"}) {
      INFO(key);
      CHECK(side[key].as<int>() == 0);
    }
  }
}

}  // namespace

TEST_CASE(
    "the identification doublet train in lockstep: the same truth over the CAN link as over LCM, "
    "the run's candump log replays with canplayer",
    "[system][rig]") {
  pin_to_cpu0();
  const std::string dir = nimble::test::scratch_dir("can_link");
  fs::create_directories(dir + "/lcm");
  fs::create_directories(dir + "/can");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  // Ideal sensing keeps the run short under emulation; the link is what differs. Inside the
  // VM on a loaded host a process can be descheduled for seconds (a controller step of 3.2 s was
  // seen): the lockstep acknowledgement timeout is raised from 2 s so that a starved vCPU is
  // not taken for a stalled participant; this test is about the truth, not about timing.
  const std::string common =
      "--clock lockstep --set run.controller_input=truth --set processes=[plant,controller] "
      "--set lockstep.ack_timeout_ms=30000";
  const RunResult over_lcm = rig_run(scenario, dir + "/lcm", common);
  INFO(over_lcm.output);
  REQUIRE(over_lcm.exit_code == 0);
  const RunResult over_can = rig_run(scenario, dir + "/can", common + " --set actuator_link=can");
  INFO(over_can.output);
  REQUIRE(over_can.exit_code == 0);
  CHECK(over_can.summary["controlled"].as<bool>());
  CHECK(over_can.summary["returned_to_hover"].as<bool>());

  // Bit for bit the same truth.
  const auto a = truth_payloads(dir + "/lcm/run.lcmlog"), b = truth_payloads(dir + "/can/run.lcmlog");
  REQUIRE(a.size() == 6001);
  CHECK(differing(a, b) == 0);

  // Every command crossed the bus; both sides report clean health.
  check_link_carried(over_can.summary, 3072, false);
  const YAML::Node ch = over_can.summary["channels"];
  const YAML::Node rig = over_can.summary["can"]["can_rig"];

  // The rig side's candump log: every frame of the run, replayable.
  const std::string candump = rig["candump_file"].as<std::string>();
  CHECK(candump == fs::absolute(dir + "/can/run.lcmlog.candump").string());
  std::vector<CandumpRecord> records;
  {
    std::ifstream in(candump);
    REQUIRE(in.good());
    std::string line;
    while (std::getline(in, line)) {
      const auto rec = parse_candump_line(line);
      REQUIRE(rec);
      records.push_back(*rec);
    }
  }
  CHECK(static_cast<int>(records.size()) == rig["candump_lines"].as<int>());
  CHECK(records.size() == 2 * 3072 + 3 * ch[kActuatorFeedback]["count"].as<std::size_t>());
  // Its commands decode as the run's commands did.
  CommandDecoder decoder;
  for (const auto& rec : records) {
    actuator_command_t cmd;
    decoder.decode(rec.frame, &cmd);
  }
  CHECK(decoder.stats().messages == 3072);
  CHECK(decoder.stats().bad_checksum == 0);
  CHECK(decoder.stats().stale_counter == 0);

  // canplayer sends the first 600 frames of the log on this vcan0, exactly as logged.
  const std::string head = dir + "/head.candump";
  REQUIRE(run("head -n 600 " + candump + " > " + head) == 0);
  CanSocketOptions opts = receive_all();
  // Room for all 600 frames: a reader thread starved by a loaded host must not lose any.
  opts.receive_buffer_bytes = 1 << 20;
  CanSocket listener = CanSocket::open(kIf, opts);
  std::vector<can_frame> replayed;
  std::atomic<bool> done{false};
  std::thread reader([&] {
    ReceivedFrame rx;
    while (replayed.size() < 600) {
      const ReceiveResult r = listener.receive(&rx, 200);
      if (r == ReceiveResult::kFrame)
        replayed.push_back(rx.frame);
      else if (done)
        break;
    }
  });
  const int played = run("canplayer -t -g 1 -I " + head + " " + kIf + "=" + kIf);
  done = true;
  reader.join();
  REQUIRE(played == 0);
  REQUIRE(replayed.size() == 600);
  std::size_t mismatched = 0;
  for (std::size_t i = 0; i < replayed.size(); ++i) mismatched += !same_frame(replayed[i], records[i].frame);
  CHECK(mismatched == 0);
  fs::remove_all(dir);
}

TEST_CASE(
    "can_bridge.fd: commands go out as FD frames with bit rate switch, FD and classical feedback frames "
    "become ACTUATOR_FB_CAN, FD frames of another length are wrong_length",
    "[bridge][fd]") {
  ensure_fd_interface();
  Bridge flight(kFlightProcess, true);
  CanSocket listener = fd_listener();

  const actuator_command_t cmd = sample_command(41);
  flight.node.node().bus().publish(kActuatorCommand, cmd);
  REQUIRE(flight.node.node().bus().handle_timeout(1000) > 0);
  CommandEncoder reference;
  expect_frames(listener, reference.encode(cmd), true);

  // Feedback as FD frames from cansend (`ID##1DATA`), then as classical frames.
  actuator_feedback_t fb = motor_feedback(41);
  FeedbackEncoder fenc;
  REQUIRE(run(send_all(fenc.encode(fb), [](const can_frame& f) { return cansend_fd(f, hex(f)); })) == 0);
  flight.pump();
  REQUIRE(flight.feedback.size() == 1);
  check_motor_feedback(flight.feedback.front(), 41);

  fb.cmd_seq = 42;
  REQUIRE(run(send_all(fenc.encode(fb), [](const can_frame& f) { return cansend(f, -1, kFdIf); })) == 0);
  flight.pump();
  REQUIRE(flight.feedback.size() == 2);
  check_motor_feedback(flight.feedback.back(), 42);

  // FD frames of 12 and 5 bytes under a feedback identifier: wrong length, reported, dropped.
  const auto next = fenc.encode(fb);
  REQUIRE(run(cansend_fd(next[0], hex(next[0]) + "00112233") + " && " + cansend_fd(next[0], hex(next[0], 5))) == 0);
  flight.pump();
  CHECK(flight.feedback.size() == 2);
  const can_health_t& h = flight.health.back();
  CHECK(h.interface_name == kFdIf);
  CHECK(h.messages_to_can == 1);
  CHECK(h.messages_to_lcm == 2);
  CHECK(h.frames_sent == 2);
  CHECK(h.frames_received == 8);
  CHECK(h.rejected_wrong_length == 2);
  CHECK(h.rejected_stale_counter == 0);
  CHECK(h.send_dropped == 0);
  CHECK(flight.fault_mentions("dropped FD frame 0x181 [12]"));
  CHECK(flight.fault_mentions("wrong_length"));
}

TEST_CASE("can_bridge.fd: FD command frames from cansend become ACTUATOR_CMD_CAN, feedback goes out as FD frames",
          "[bridge][fd]") {
  ensure_fd_interface();
  Bridge rig(kRigProcess, true);
  CommandEncoder enc;
  REQUIRE(run(send_all(enc.encode(sample_command(1000)), [](const can_frame& f) { return cansend_fd(f, hex(f)); })) ==
          0);
  rig.pump();
  REQUIRE(rig.commands.size() == 1);
  check_sample_command(rig.commands.back(), 1000);

  CanSocket listener = fd_listener();
  const actuator_feedback_t fb = plant_feedback(1000);
  rig.node.node().bus().publish(kActuatorFeedback, fb);
  REQUIRE(rig.node.node().bus().handle_timeout(1000) > 0);
  FeedbackEncoder reference;
  expect_frames(listener, reference.encode(fb), true);
  rig.pump();
  CHECK(rig.health.back().frames_sent == 3);
  CHECK(rig.health.back().frames_received == 2);
  CHECK(rig.health.back().messages_to_lcm == 1);
}

TEST_CASE("the bridge refuses a control rate outside the controller's range, before it opens a socket", "[bridge]") {
  const nimble::Scenario scenario = nimble::load_scenario(kConfigs + "id_doublet_train_fast.yaml",
                                                          {{"actuator_link", "can"}, {"controller.rate_hz", "10"}});
  try {
    CanBridgeNode node(scenario, {kRigProcess, scenario.file, "memq://"});
    FAIL("no exception");
  } catch (const nimble::ConfigError& e) {
    CHECK_THAT(std::string(e.what()),
               Catch::Matchers::Contains("controller.rate_hz") && Catch::Matchers::Contains("10"));
  }
}

TEST_CASE("can_bridge.fd on an interface with the classical MTU names the fix", "[bridge][fd]") {
  pin_to_cpu0();
  const std::string classical_if = "vcan_cc";
  REQUIRE(run("ip link add dev " + classical_if + " type vcan && ip link set " + classical_if +
              " mtu 16 && ip link set " + classical_if + " up") == 0);
  const nimble::Scenario scenario = nimble::load_scenario(
      kConfigs + "id_doublet_train_fast.yaml",
      {{"actuator_link", "can"}, {"can_bridge.interface", classical_if}, {"can_bridge.fd", "true"}});
  try {
    CanBridgeNode node(scenario, {kRigProcess, scenario.file, "memq://"});
    FAIL("no exception");
  } catch (const CanError& e) {
    CHECK_THAT(std::string(e.what()), Catch::Matchers::Contains("'" + classical_if + "' has MTU 16") &&
                                          Catch::Matchers::Contains("ip link set " + classical_if + " mtu 72"));
  }
  CHECK(run("ip link del dev " + classical_if) == 0);
}

TEST_CASE("rig run's interface set-up with can_bridge.fd: a vcan it creates gets MTU 72, MTU 16 names the fix",
          "[launcher][fd]") {
  using nimble::launcher::ensure_can_interface;
  const auto mtu = [](const std::string& name) {
    const int fd = ::socket(AF_INET, SOCK_DGRAM, 0);
    REQUIRE(fd >= 0);
    ifreq ifr{};
    std::strncpy(ifr.ifr_name, name.c_str(), IFNAMSIZ - 1);
    const int rc = ::ioctl(fd, SIOCGIFMTU, &ifr);
    ::close(fd);
    REQUIRE(rc == 0);
    return ifr.ifr_mtu;
  };
  CHECK(ensure_can_interface("vcan_fdnew", true, true) == "");
  CHECK(mtu("vcan_fdnew") == 72);
  CHECK(ensure_can_interface("vcan_fdnew", true, true) == "");  // existing, MTU 72, up

  REQUIRE(run("ip link add dev vcan_cc type vcan && ip link set vcan_cc mtu 16") == 0);
  CHECK(ensure_can_interface("vcan_cc", true, false) == "");  // classical: fine (and raised)
  const std::string problem = ensure_can_interface("vcan_cc", true, true);
  CHECK_THAT(problem, Catch::Matchers::Contains("'vcan_cc' has MTU 16") &&
                          Catch::Matchers::Contains("ip link set vcan_cc mtu 72") &&
                          Catch::Matchers::Contains("can_bridge.fd"));
  CHECK(mtu("vcan_cc") == 16);  // an existing interface is never changed
  CHECK(run("ip link del dev vcan_cc && ip link del dev vcan_fdnew") == 0);
}

TEST_CASE("rig run over the CAN link with can_bridge.fd: every command crosses in FD frames", "[system][rig][fd]") {
  pin_to_cpu0();
  const std::string dir = nimble::test::scratch_dir("can_fd_link");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  const RunResult r = rig_run(scenario, dir,
                              "--clock lockstep --set duration_s=1 --set actuator_link=can --set can_bridge.fd=true "
                              "--set run.controller_input=truth --set processes=[plant,controller] "
                              "--set lockstep.ack_timeout_ms=30000");
  INFO(r.output);
  REQUIRE(r.exit_code == 0);
  check_link_carried(r.summary, 512, true);
  const YAML::Node ch = r.summary["channels"];
  const YAML::Node rig = r.summary["can"]["can_rig"];
  // The rig side's candump log holds FD lines (ID##1...) that decode as the run's commands.
  const std::string candump = rig["candump_file"].as<std::string>();
  std::ifstream in(candump);
  REQUIRE(in.good());
  std::string line;
  std::size_t lines = 0, fd_with_brs = 0;
  CommandDecoder decoder;
  while (std::getline(in, line)) {
    INFO(line);
    const auto rec = parse_candump_line(line);
    REQUIRE(rec);
    ++lines;
    if (rec->is_fd && rec->fd_frame.len == 8 && (rec->fd_frame.flags & CANFD_BRS)) ++fd_with_brs;
    actuator_command_t cmd;
    decoder.decode(rec->frame, &cmd);
  }
  CHECK(static_cast<int>(lines) == rig["candump_lines"].as<int>());
  CHECK(lines == 2 * 512 + 3 * ch[kActuatorFeedback]["count"].as<std::size_t>());
  CHECK(fd_with_brs == lines);
  CHECK(decoder.stats().messages == 512);
  CHECK(decoder.stats().unknown_id == 3 * ch[kActuatorFeedback]["count"].as<std::size_t>());  // the feedback frames
  CHECK(decoder.stats().wrong_length == 0);
  CHECK(decoder.stats().bad_checksum == 0);
  CHECK(decoder.stats().stale_counter == 0);
  fs::remove_all(dir);
}

TEST_CASE(
    "faults of the CAN link over vcan0 in lockstep: the frames lost and the truth are those of the in-process run",
    "[system][rig][faults]") {
  pin_to_cpu0();
  const std::string dir = nimble::test::scratch_dir("can_link_faults");
  fs::create_directories(dir + "/vcan");
  fs::create_directories(dir + "/inprocess");
  const std::string scenario = kConfigs + "id_doublet_train_fast.yaml";
  // Loss, then a bus-off, on the real SocketCAN link: every decision comes from the seed at the
  // sending side, so the real bus and the in-process frame bus lose the same frames.
  const std::string common =
      "--set duration_s=2 --set actuator_link=can --set run.controller_input=truth --set processes=[plant,controller] "
      "--set lockstep.ack_timeout_ms=30000 --set 'faults=[{target: CAN, kind: loss, start_s: 0.5, duration_s: 0.5, "
      "params: {probability: 0.2}}, {target: CAN, kind: bus_off, start_s: 1.2, duration_s: 0.2}]'";
  const RunResult over_vcan = rig_run(scenario, dir + "/vcan", "--clock lockstep " + common);
  INFO(over_vcan.output);
  // 0.2 s of safe-state hold in the middle of the doublets: the vehicle may well be lost (exit 1);
  // what matters is that both runs agree.
  REQUIRE(over_vcan.summary);
  CHECK((over_vcan.exit_code == 0 || over_vcan.exit_code == 1));
  const RunResult in_process = rig_run(scenario, dir + "/inprocess", "--clock inprocess " + common);
  INFO(in_process.output);
  REQUIRE(in_process.summary);
  CHECK(in_process.exit_code == over_vcan.exit_code);
  CHECK(in_process.summary["sim_time_s"].as<double>() == Approx(2.0).margin(0.002));
  CHECK(over_vcan.summary["sim_time_s"].as<double>() == Approx(2.0).margin(0.002));
  const int drops = over_vcan.summary["channels"][kActuatorCommandCan]["drops"].as<int>();
  CHECK(drops > 0.2 * 1024 * 0.36 + 100);  // the loss window and the 0.2 s bus-off (102 commands)
  CHECK(drops == in_process.summary["channels"][kActuatorCommandCan]["drops"].as<int>());
  bool bus_off = false;
  for (const auto& f : over_vcan.summary["faults"]) {
    bus_off |= f["code"].as<int>() == fault_event_t::CODE_CAN_ERROR_FRAME &&
               f["message"].as<std::string>().find("bus-off") != std::string::npos;
  }
  CHECK(bus_off);
  CHECK(differing(truth_payloads(dir + "/vcan/run.lcmlog"), truth_payloads(dir + "/inprocess/run.lcmlog")) == 0);
  fs::remove_all(dir);
}
