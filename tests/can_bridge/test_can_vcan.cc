// Tests on a real SocketCAN interface, vcan0, created by tools/canvm/canvm ctest-wrap (in a qemu
// VM on kernels without CAN, else in a private network namespace). One executable = one VM boot.
// Uses can-utils (cansend, candump, canplayer) and iproute2's tc from PATH.
// The CAN FD cases use vcan1, which they create with the CAN FD MTU (72; a vcan's default on
// current kernels, set explicitly all the same), and vcan_cc with the classical MTU (16).

#include <fcntl.h>
#include <net/if.h>
#include <linux/can/error.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <string>
#include <vector>

#include <catch2/catch.hpp>

#include "can_bridge/can_socket.h"
#include "can_bridge/candump_log.h"
#include "can_bridge/codec.h"
#include "can_bridge/crc8.h"
#include "can_bridge/frame_layout.h"
#include "tests/support/scratch.h"

using namespace nimble::can;
using Catch::Matchers::Contains;
using nimble::actuator_command_t;
using nimble::actuator_feedback_t;

namespace {

const std::string kIf = "vcan0";
constexpr int kTimeoutMs = 3000;

int64_t realtime_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

CanSocketOptions send_only() {
  CanSocketOptions o;
  o.filters.clear();
  o.error_frames = false;
  return o;
}

CanSocketOptions receive_all() {
  CanSocketOptions o;
  o.receive_all = true;
  return o;
}

/// Receives the next data frame (error frames are skipped); fails the test on timeout.
ReceivedFrame next_data(CanSocket& s) {
  for (;;) {
    ReceivedFrame rx;
    const ReceiveResult r = s.receive(&rx, kTimeoutMs);
    REQUIRE(r == ReceiveResult::kFrame);
    if (!rx.is_error_frame) return rx;
  }
}

bool nothing_pending(CanSocket& s, int wait_ms) {
  ReceivedFrame rx;
  return s.receive(&rx, wait_ms) == ReceiveResult::kTimeout;
}

bool same_frame(const can_frame& a, const can_frame& b) {
  return a.can_id == b.can_id && a.len == b.len && std::memcmp(a.data, b.data, a.len) == 0;
}

std::string hex(const can_frame& f) {
  std::string s;
  char b[3];
  for (unsigned i = 0; i < f.len; ++i) {
    std::snprintf(b, sizeof b, "%02X", f.data[i]);
    s += b;
  }
  return s;
}

int run(const std::string& cmd) {
  INFO(cmd);
  const int status = std::system(cmd.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128;
}

/// A child process whose stdout (and stderr) is read line by line.
class Child {
 public:
  explicit Child(const std::vector<std::string>& argv) {
    int fds[2];
    REQUIRE(::pipe(fds) == 0);
    pid_ = ::fork();
    REQUIRE(pid_ >= 0);
    if (pid_ == 0) {
      ::dup2(fds[1], 1);
      ::dup2(fds[1], 2);
      ::close(fds[0]);
      ::close(fds[1]);
      std::vector<char*> args;
      for (const auto& a : argv) args.push_back(const_cast<char*>(a.c_str()));
      args.push_back(nullptr);
      ::execvp(args[0], args.data());
      std::fprintf(stderr, "exec %s: %s\n", args[0], std::strerror(errno));
      ::_exit(127);
    }
    ::close(fds[1]);
    fd_ = fds[0];
  }
  ~Child() {
    if (pid_ > 0) {
      ::kill(pid_, SIGTERM);
      ::waitpid(pid_, nullptr, 0);
    }
    if (fd_ >= 0) ::close(fd_);
  }
  Child(const Child&) = delete;
  Child& operator=(const Child&) = delete;

  /// Next output line, or false if none arrives within timeout_ms.
  bool read_line(std::string* line, int timeout_ms) {
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
    for (;;) {
      const auto nl = buffer_.find('\n');
      if (nl != std::string::npos) {
        *line = buffer_.substr(0, nl);
        buffer_.erase(0, nl + 1);
        return true;
      }
      const auto left =
          std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
      if (left.count() <= 0) return false;
      pollfd p{fd_, POLLIN, 0};
      if (::poll(&p, 1, static_cast<int>(left.count())) <= 0) continue;
      char buf[4096];
      const ssize_t n = ::read(fd_, buf, sizeof buf);
      if (n <= 0) return false;
      buffer_.append(buf, static_cast<std::size_t>(n));
    }
  }

 private:
  pid_t pid_ = -1;
  int fd_ = -1;
  std::string buffer_;
};

actuator_command_t command(int64_t seq) {
  actuator_command_t c{};
  c.seq = seq;
  c.mode = (seq % 2) ? actuator_command_t::MODE_DELTA_F : actuator_command_t::MODE_LEFT_RIGHT;
  c.flap_freq_left_radps = 100.0 + 0.37 * static_cast<double>(seq % 50);
  c.flap_freq_right_radps = 104.0 - 0.21 * static_cast<double>(seq % 50);
  c.delta_f_radps = c.flap_freq_left_radps - c.flap_freq_right_radps;
  c.flap_freq_collective_radps = 0.5 * (c.flap_freq_left_radps + c.flap_freq_right_radps);
  c.throttle_pct = 55.5;
  c.dihedral_rad = 0.001 * static_cast<double>(seq % 300) - 0.15;
  c.wing_root_rad = -0.0005 * static_cast<double>(seq % 100);
  c.rolling_counter = static_cast<int8_t>(seq % 16);
  return c;
}

std::vector<can_frame> traffic(int commands) {
  CommandEncoder cenc;
  FeedbackEncoder fenc;
  std::vector<can_frame> frames;
  for (int i = 0; i < commands; ++i) {
    for (const can_frame& f : cenc.encode(command(i))) frames.push_back(f);
    if (i % 5 == 0) {
      actuator_feedback_t fb{};
      fb.flap_freq_left_radps = 100.0;
      fb.flap_freq_right_radps = 101.0;
      fb.throttle_pct = 55.5;
      fb.cmd_seq = i;
      fb.cmd_age_us = 700 + i;
      for (const can_frame& f : fenc.encode(fb)) frames.push_back(f);
    }
  }
  return frames;
}

/// vcan1 with the CAN FD MTU, created (once) by the FD cases.
const std::string kFdIf = "vcan1";

void ensure_fd_interface() {
  if (::if_nametoindex(kFdIf.c_str()) != 0) return;
  // A vcan's MTU can only be changed while it is down, as it is after `ip link add`.
  REQUIRE(run("ip link add dev " + kFdIf + " type vcan && ip link set " + kFdIf + " mtu 72 && ip link set " + kFdIf +
              " up") == 0);
}

/// Sends a marker frame until `rx` receives one with a kernel timestamp. The first socket that asks
/// for receive timestamps switches them on for the whole kernel through a deferred work item; frames
/// queued before it ran carry none.
void wait_for_timestamps(CanSocket& tx, CanSocket& rx) {
  can_frame marker{};
  marker.can_id = 0x7F1;
  marker.len = 1;
  for (int i = 0; i < 200; ++i) {
    REQUIRE(tx.send(marker) == SendResult::kSent);
    ReceivedFrame got;
    bool stamped = false;
    while (rx.receive(&got, 10) == ReceiveResult::kFrame) stamped = got.has_kernel_time;
    if (stamped) return;
  }
  FAIL("no kernel receive timestamps after 200 frames");
}

CanSocketOptions fd_options(CanSocketOptions o) {
  o.fd = true;
  return o;
}

/// The flags the kernel may add on its own: CANFD_FDF (kernels with CAN XL mark every FD frame).
bool same_fd_frame(const canfd_frame& got, const canfd_frame& sent) {
  return got.can_id == sent.can_id && got.len == sent.len && (got.flags & ~CANFD_FDF) == (sent.flags & ~CANFD_FDF) &&
         std::memcmp(got.data, sent.data, sent.len) == 0;
}

/// The rig's traffic as FD frames of 8 bytes with bit rate switch, as the bridge sends it with fd.
std::vector<canfd_frame> fd_traffic(int commands) {
  std::vector<canfd_frame> out;
  for (const can_frame& f : traffic(commands)) out.push_back(to_fd_frame(f, CANFD_BRS));
  return out;
}

canfd_frame fd_frame(uint32_t id, uint8_t flags, unsigned len, uint8_t seed) {
  canfd_frame f{};
  f.can_id = id;
  f.flags = flags;
  f.len = static_cast<uint8_t>(len);
  for (unsigned i = 0; i < len; ++i) f.data[i] = static_cast<uint8_t>(seed + 13 * i);
  return f;
}

std::string temp_path(const std::string& name) { return nimble::test::scratch_path(name); }

}  // namespace

TEST_CASE("frames sent with CanSocket arrive bit-exact with monotonic kernel timestamps", "[vcan]") {
  CanSocket tx = CanSocket::open(kIf, send_only());
  CanSocket rx = CanSocket::open(kIf);  // rig filters, error frames, timestamps
  {
    // rx keeps the kernel's timestamping on; a second socket sees the markers rx filters out.
    CanSocket warm_tx = CanSocket::open(kIf, send_only());
    CanSocket warm = CanSocket::open(kIf, receive_all());
    wait_for_timestamps(warm_tx, warm);
  }
  const std::vector<can_frame> frames = traffic(60);
  const int64_t t_start = realtime_ns();
  for (const can_frame& f : frames) REQUIRE(tx.send(f) == SendResult::kSent);

  CommandDecoder cdec;
  FeedbackDecoder fdec;
  int64_t last_ts = 0;
  for (const can_frame& sent : frames) {
    const ReceivedFrame got = next_data(rx);
    INFO("frame " << std::hex << sent.can_id);
    CHECK(same_frame(got.frame, sent));
    CHECK(std::memcmp(&got.frame.data, &sent.data, 8) == 0);
    REQUIRE(got.has_kernel_time);
    CHECK(got.kernel_time_ns >= last_ts);
    CHECK(got.kernel_time_ns >= t_start - 1000000);
    CHECK(got.kernel_time_ns <= realtime_ns());
    last_ts = got.kernel_time_ns;
    actuator_command_t c;
    actuator_feedback_t fb;
    const DecodeResult r =
        (got.frame.can_id & CAN_SFF_MASK) < kFbMotor.id ? cdec.decode(got.frame, &c) : fdec.decode(got.frame, &fb);
    CHECK((r == DecodeResult::kAccepted || r == DecodeResult::kMessageComplete));
  }
  CHECK(nothing_pending(rx, 50));
  CHECK(tx.stats().frames_sent == frames.size());
  CHECK(tx.stats().send_enobufs == 0);
  CHECK(rx.stats().frames_received == frames.size());
  CHECK(rx.stats().missing_timestamps == 0);
  CHECK(rx.stats().receive_dropped == 0);
  CHECK(cdec.stats().messages == 60);
  CHECK(fdec.stats().messages == 12);
  CHECK(cdec.stats().dropped() + fdec.stats().dropped() == 0);
}

TEST_CASE("receive filters pass only the rig's identifiers", "[vcan]") {
  CanSocket tx = CanSocket::open(kIf, send_only());
  CanSocket rig = CanSocket::open(kIf);
  CanSocket all = CanSocket::open(kIf, receive_all());
  can_frame other{};
  other.can_id = 0x123;
  other.len = 2;
  can_frame extended = other;
  extended.can_id = kCmdFlap.id | CAN_EFF_FLAG;  // same number, 29-bit: not a rig frame
  const can_frame rig_frame = traffic(1)[0];
  for (const can_frame& f : {other, extended, rig_frame}) REQUIRE(tx.send(f) == SendResult::kSent);
  CHECK(same_frame(next_data(rig).frame, rig_frame));
  CHECK(nothing_pending(rig, 100));
  CHECK(same_frame(next_data(all).frame, other));
  CHECK(same_frame(next_data(all).frame, extended));
  CHECK(same_frame(next_data(all).frame, rig_frame));
}

TEST_CASE("frames sent with cansend arrive and decode, bad ones are counted", "[vcan][can-utils]") {
  CanSocket rx = CanSocket::open(kIf, receive_all());
  // A command written by hand from the documented layout: left 100.00 rad/s (0x2710), right
  // 90.00 rad/s (0x2328), throttle 50.00 % (0x1388), mode 0, counter 3; dihedral -0.1234 rad
  // (0xFB2E), wing root 0.5 rad (0x1388), seq 0x0042.
  uint8_t flap[8] = {0x10, 0x27, 0x28, 0x23, 0x88, 0x13, 0x30, 0};
  uint8_t servo[8] = {0x2E, 0xFB, 0x88, 0x13, 0x42, 0x00, 0x30, 0};
  flap[7] = frame_crc(0x101, flap, 7);
  servo[7] = frame_crc(0x102, servo, 7);
  can_frame f{};
  f.len = 8;
  std::memcpy(f.data, flap, 8);
  const std::string flap_hex = hex(f);
  std::memcpy(f.data, servo, 8);
  const std::string servo_hex = hex(f);
  std::string bad_crc_hex = servo_hex;
  bad_crc_hex[15] = bad_crc_hex[15] == '0' ? '1' : '0';
  REQUIRE(run("cansend " + kIf + " 101#" + flap_hex + " && cansend " + kIf + " 102#" + servo_hex + " && cansend " +
              kIf + " 1FF#0011 && cansend " + kIf + " 101#1027 && cansend " + kIf + " 102#" + bad_crc_hex) == 0);

  CommandDecoder dec;
  actuator_command_t out{};
  CHECK(dec.decode(next_data(rx).frame, &out) == DecodeResult::kAccepted);
  REQUIRE(dec.decode(next_data(rx).frame, &out) == DecodeResult::kMessageComplete);
  CHECK(out.flap_freq_left_radps == Approx(100.0));
  CHECK(out.flap_freq_right_radps == Approx(90.0));
  CHECK(out.delta_f_radps == Approx(10.0));
  CHECK(out.throttle_pct == Approx(50.0));
  CHECK(out.mode == actuator_command_t::MODE_LEFT_RIGHT);
  CHECK(out.dihedral_rad == Approx(-0.1234));
  CHECK(out.wing_root_rad == Approx(0.5));
  CHECK(out.seq == 0x42);
  CHECK(out.rolling_counter == 3);
  CHECK(dec.decode(next_data(rx).frame, &out) == DecodeResult::kUnknownId);
  CHECK(dec.decode(next_data(rx).frame, &out) == DecodeResult::kWrongLength);
  CHECK(dec.decode(next_data(rx).frame, &out) == DecodeResult::kBadChecksum);
  CHECK(dec.stats().messages == 1);
  CHECK(dec.stats().dropped() == 3);
}

TEST_CASE("candump -L prints our frames exactly as encoded", "[vcan][can-utils]") {
  Child candump({"stdbuf", "-oL", "candump", "-L", kIf});
  CanSocket tx = CanSocket::open(kIf, send_only());
  // handshake: candump is listening once it prints a marker frame
  can_frame marker{};
  marker.can_id = 0x7F0;
  marker.len = 1;
  std::string line;
  bool listening = false;
  for (int i = 0; i < 100 && !listening; ++i) {
    tx.send(marker);
    while (candump.read_line(&line, 50)) {
      if (line.find(" " + kIf + " 7F0#") != std::string::npos) listening = true;
    }
  }
  REQUIRE(listening);
  const std::vector<can_frame> frames = traffic(10);
  for (const can_frame& f : frames) REQUIRE(tx.send(f) == SendResult::kSent);
  std::size_t matched = 0;
  while (matched < frames.size() && candump.read_line(&line, kTimeoutMs)) {
    if (line.find(" " + kIf + " 7F0#") != std::string::npos) continue;  // late marker copies
    INFO(line);
    const auto rec = parse_candump_line(line);
    REQUIRE(rec);
    CHECK(rec->interface == kIf);
    CHECK(same_frame(rec->frame, frames[matched]));
    // our writer produces the same text as candump for the same frame and time
    CHECK(line == format_candump_line(frames[matched], rec->time_ns, kIf));
    ++matched;
  }
  CHECK(matched == frames.size());
}

TEST_CASE("a candump log written by CandumpWriter is replayed by canplayer identically", "[vcan][can-utils]") {
  const std::string path = temp_path("rig_canplayer") + ".log";
  const std::vector<can_frame> frames = traffic(8);
  {
    CandumpWriter writer(path);
    int64_t t = realtime_ns();
    for (const can_frame& f : frames) {
      REQUIRE(writer.write(f, t, kIf));
      t += 1000000;  // 1 ms apart
    }
    REQUIRE(writer.flush());
  }
  CanSocket rx = CanSocket::open(kIf, receive_all());
  REQUIRE(run("canplayer -I " + path + " " + kIf + "=" + kIf) == 0);
  for (const can_frame& f : frames) {
    const ReceivedFrame got = next_data(rx);
    CHECK(same_frame(got.frame, f));
  }
  CHECK(nothing_pending(rx, 100));
  std::filesystem::remove(path);
}

TEST_CASE("a log of received frames with their kernel timestamps replays identically", "[vcan][can-utils]") {
  const std::string path = temp_path("rig_rxlog") + ".log";
  const std::vector<can_frame> frames = traffic(8);
  CanSocket tx = CanSocket::open(kIf, send_only());
  CanSocket rx = CanSocket::open(kIf, receive_all());
  {
    CandumpWriter writer(path);
    for (const can_frame& f : frames) {
      REQUIRE(tx.send(f) == SendResult::kSent);
      const ReceivedFrame got = next_data(rx);
      REQUIRE(writer.write(got.frame, got.kernel_time_ns, kIf));
    }
  }
  REQUIRE(run("canplayer -I " + path + " " + kIf + "=" + kIf) == 0);
  for (const can_frame& f : frames) CHECK(same_frame(next_data(rx).frame, f));
  CHECK(nothing_pending(rx, 100));
  std::filesystem::remove(path);
}

TEST_CASE("error frames sent through the kernel are received, decoded and counted", "[vcan][error]") {
  // vcan has no controller that could report bus errors; an error frame written to a raw socket
  // travels the same receive path (CAN_RAW_ERR_FILTER) as one from a driver.
  CanSocket tx = CanSocket::open(kIf, send_only());
  CanSocket with_errors = CanSocket::open(kIf);
  CanSocketOptions no_err;
  no_err.error_frames = false;
  CanSocket without_errors = CanSocket::open(kIf, no_err);
  can_frame err{};
  err.can_id = CAN_ERR_FLAG | CAN_ERR_BUSOFF | CAN_ERR_CRTL | CAN_ERR_CNT;
  err.len = CAN_ERR_DLC;
  err.data[1] = CAN_ERR_CRTL_TX_PASSIVE;
  err.data[6] = 255;
  err.data[7] = 3;
  REQUIRE(tx.send(err) == SendResult::kSent);

  ReceivedFrame rx;
  REQUIRE(with_errors.receive(&rx, kTimeoutMs) == ReceiveResult::kFrame);
  CHECK(rx.is_error_frame);
  CHECK(rx.error.bus_off);
  CHECK(rx.error.error_passive);
  CHECK(rx.error.tx_error_count == 255);
  CHECK(rx.error.description == "controller: TX error-passive; bus-off; TEC 255 REC 3");
  CHECK(rx.has_kernel_time);
  CHECK(with_errors.stats().error_frames == 1);
  CHECK(with_errors.stats().frames_received == 0);
  CHECK(nothing_pending(without_errors, 100));

  CommandDecoder dec;  // an error frame handed to a decoder is counted, not decoded
  CHECK(dec.decode(rx.frame, nullptr) == DecodeResult::kErrorFrame);
  CHECK(dec.stats().error_frames == 1);
}

TEST_CASE("a full transmit queue gives ENOBUFS, which is retried, counted and never a crash", "[vcan][enobufs]") {
  // vcan normally has no queue; a token-bucket qdisc (8 kbit/s, 4 frames deep) makes the
  // kernel drop and report ENOBUFS the way a real CAN controller's full queue does.
  struct Qdisc {
    Qdisc() { REQUIRE(run("tc qdisc replace dev " + kIf + " root tbf rate 8kbit burst 32 limit 64") == 0); }
    ~Qdisc() { remove(); }
    void remove() {
      if (active) run("tc qdisc del dev " + kIf + " root");
      active = false;
    }
    bool active = true;
  } qdisc;
  CanSocketOptions opt = send_only();
  opt.retry.max_retries = 3;
  opt.retry.first_backoff = std::chrono::microseconds(50);
  opt.retry.max_backoff = std::chrono::microseconds(200);
  int sent = 0, dropped = 0, errors = 0;
  {
    CanSocket tx = CanSocket::open(kIf, opt);
    const std::vector<can_frame> frames = traffic(100);
    for (const can_frame& f : frames) {
      switch (tx.send(f)) {
        case SendResult::kSent: ++sent; break;
        case SendResult::kDropped: ++dropped; break;
        case SendResult::kError: ++errors; break;
      }
    }
    const CanSocketStats& s = tx.stats();
    INFO("sent " << sent << " dropped " << dropped << " ENOBUFS " << s.send_enobufs << " EAGAIN " << s.send_eagain
                 << " retries " << s.send_retries);
    CHECK(s.send_enobufs > 0);
    CHECK(s.send_retries > 0);
    CHECK(dropped > 0);
    CHECK(errors == 0);
    CHECK(s.send_errors == 0);
    CHECK(static_cast<std::size_t>(sent + dropped) == frames.size());
    CHECK(s.frames_sent == static_cast<uint64_t>(sent));
    CHECK(s.send_dropped == static_cast<uint64_t>(dropped));
    CHECK(s.send_retries <= s.send_enobufs + s.send_eagain);
    CHECK(s.last_errno == ENOBUFS);
  }
  qdisc.remove();
  CanSocket tx = CanSocket::open(kIf, opt);
  CanSocket rx = CanSocket::open(kIf);
  const can_frame f = traffic(1)[0];
  CHECK(tx.send(f) == SendResult::kSent);
  CHECK(same_frame(next_data(rx).frame, f));
}

TEST_CASE("a receive queue overflow is counted as dropped (SO_RXQ_OVFL)", "[vcan]") {
  CanSocketOptions small;
  small.receive_buffer_bytes = 1;  // the kernel rounds up to its minimum (a few frames)
  CanSocket rx = CanSocket::open(kIf, small);
  CanSocket tx = CanSocket::open(kIf, send_only());
  const std::vector<can_frame> frames = traffic(100);
  for (const can_frame& f : frames) REQUIRE(tx.send(f) == SendResult::kSent);
  std::size_t received = 0;
  ReceivedFrame got;
  while (rx.receive(&got, 100) == ReceiveResult::kFrame) ++received;
  INFO("received " << received << " of " << frames.size());
  CHECK(received < frames.size());
  // the kernel reports the drop count with each frame queued after the drops
  REQUIRE(tx.send(frames[0]) == SendResult::kSent);
  REQUIRE(rx.receive(&got, kTimeoutMs) == ReceiveResult::kFrame);
  CHECK(rx.stats().receive_dropped == frames.size() - received);
}

TEST_CASE("opening a missing or down interface names it and says what to do", "[vcan]") {
  try {
    CanSocket::open("vcan_missing");
    FAIL("no exception");
  } catch (const CanError& e) {
    CHECK(e.errno_value() == ENODEV);
    CHECK_THAT(std::string(e.what()), Contains("'vcan_missing'") && Contains("ip link add dev vcan_missing type vcan"));
  }
  REQUIRE(run("ip link add dev vcan_down type vcan") == 0);
  try {
    CanSocket::open("vcan_down");
    FAIL("no exception");
  } catch (const CanError& e) {
    CHECK(e.errno_value() == ENETDOWN);
    CHECK_THAT(std::string(e.what()), Contains("'vcan_down' is down") && Contains("ip link set vcan_down up"));
  }
  CHECK(run("ip link del dev vcan_down") == 0);
  try {
    CanSocket::open("lo");
    FAIL("no exception");
  } catch (const CanError& e) {
    CHECK_THAT(std::string(e.what()), Contains("'lo'"));
  }
}

TEST_CASE("CAN FD frames sent with CanSocket arrive bit-exact on a vcan with MTU 72", "[vcan][fd]") {
  ensure_fd_interface();
  CanSocket tx = CanSocket::open(kFdIf, fd_options(send_only()));
  CanSocket rx = CanSocket::open(kFdIf, fd_options(receive_all()));
  CanSocket classical_only = CanSocket::open(kFdIf, receive_all());  // no CAN_RAW_FD_FRAMES
  CHECK(tx.fd_enabled());
  CHECK_FALSE(classical_only.fd_enabled());
  wait_for_timestamps(tx, rx);
  while (classical_only.receive(nullptr, 0) == ReceiveResult::kFrame) {
  }
  const uint64_t received_before = rx.stats().frames_received, sent_before = tx.stats().frames_sent;
  const uint64_t classical_before = classical_only.stats().frames_received;

  // The rig's frames as FD frames, then other FD lengths, flags and a classical frame.
  std::vector<canfd_frame> frames = fd_traffic(20);
  const canfd_frame longest = fd_frame(0x101, CANFD_BRS, 64, 3);
  const canfd_frame twelve = fd_frame(0x182, 0, 12, 7);
  const canfd_frame empty = fd_frame(0x123, CANFD_BRS | CANFD_ESI, 0, 0);
  const canfd_frame extended = fd_frame(0x1ABCDEF | CAN_EFF_FLAG, CANFD_BRS, 8, 9);
  frames.insert(frames.end(), {longest, twelve, empty, extended});
  const can_frame classical = traffic(1)[0];
  const int64_t t_start = realtime_ns();
  for (const canfd_frame& f : frames) REQUIRE(tx.send(f) == SendResult::kSent);
  REQUIRE(tx.send(classical) == SendResult::kSent);

  CommandDecoder cdec;
  FeedbackDecoder fdec;
  for (const canfd_frame& sent : frames) {
    const ReceivedFrame got = next_data(rx);
    INFO("frame " << std::hex << sent.can_id << std::dec << " len " << int(sent.len));
    REQUIRE(got.is_fd);
    CHECK(same_fd_frame(got.fd_frame, sent));
    CHECK(got.fd_flags == got.fd_frame.flags);
    CHECK((got.fd_flags & CANFD_BRS) == (sent.flags & CANFD_BRS));
    REQUIRE(got.has_kernel_time);
    CHECK(got.kernel_time_ns >= t_start - 1000000);
    if (sent.len <= CAN_MAX_DLEN) {
      CHECK(same_frame(got.frame, classical_view(sent)));
    } else {
      CHECK(got.frame.can_id == sent.can_id);
      CHECK(got.frame.len == 0);
    }
    const uint32_t id = got.frame.can_id;
    if (id == kCmdFlap.id || id == kCmdServo.id) {
      actuator_command_t c;
      const DecodeResult r = cdec.decode(got.frame, &c);
      if (sent.len == 8)
        CHECK((r == DecodeResult::kAccepted || r == DecodeResult::kMessageComplete));
      else
        CHECK(r == DecodeResult::kWrongLength);
    } else if (id == kFbMotor.id || id == kFbServo.id || id == kFbStatus.id) {
      actuator_feedback_t fb;
      const DecodeResult r = fdec.decode(got.frame, &fb);
      if (sent.len == 8)
        CHECK((r == DecodeResult::kAccepted || r == DecodeResult::kMessageComplete));
      else
        CHECK(r == DecodeResult::kWrongLength);
    }
  }
  const ReceivedFrame got_classical = next_data(rx);
  CHECK_FALSE(got_classical.is_fd);
  CHECK(same_frame(got_classical.frame, classical));
  CHECK(nothing_pending(rx, 50));
  CHECK(cdec.stats().messages == 20);
  CHECK(fdec.stats().messages == 4);
  CHECK(cdec.stats().wrong_length == 1);
  CHECK(fdec.stats().wrong_length == 1);

  // A socket without CAN_RAW_FD_FRAMES sees only the classical frame.
  CHECK(same_frame(next_data(classical_only).frame, classical));
  CHECK(nothing_pending(classical_only, 50));

  CHECK(tx.stats().frames_sent - sent_before == frames.size() + 1);
  CHECK(tx.stats().fd_frames_sent == frames.size());
  CHECK(rx.stats().frames_received - received_before == frames.size() + 1);
  CHECK(rx.stats().fd_frames_received == frames.size());
  CHECK(classical_only.stats().frames_received - classical_before == 1);
  CHECK(classical_only.stats().fd_frames_received == 0);
  CHECK(rx.stats().receive_errors == 0);
}

TEST_CASE("CAN FD on an interface with the classical MTU is refused with the fix", "[vcan][fd]") {
  const std::string classical_if = "vcan_cc";
  REQUIRE(run("ip link add dev " + classical_if + " type vcan && ip link set " + classical_if +
              " mtu 16 && ip link set " + classical_if + " up") == 0);
  try {
    CanSocket::open(classical_if, fd_options(send_only()));
    FAIL("no exception");
  } catch (const CanError& e) {
    CHECK(e.interface() == classical_if);
    CHECK_THAT(std::string(e.what()),
               Contains("'" + classical_if + "' has MTU 16") && Contains("ip link set " + classical_if + " mtu 72"));
  }
  CanSocket::open(classical_if, send_only());  // classical CAN is fine there
  CHECK(run("ip link del dev " + classical_if) == 0);
  // Without fd the kernel refuses an FD frame: an error, not a crash, and no retries.
  ensure_fd_interface();
  CanSocket classical = CanSocket::open(kFdIf, send_only());
  CHECK(classical.send(fd_frame(0x101, CANFD_BRS, 8, 1)) == SendResult::kError);
  CHECK(classical.stats().send_errors == 1);
  CHECK(classical.stats().send_retries == 0);
  CHECK(classical.stats().fd_frames_sent == 0);
}

TEST_CASE("cansend FD frames arrive, candump -L prints FD frames exactly as our writer", "[vcan][fd][can-utils]") {
  ensure_fd_interface();
  CanSocket rx = CanSocket::open(kFdIf, fd_options(receive_all()));
  REQUIRE(run("cansend " + kFdIf + " 181##1DEADBEEF01020304 && cansend " + kFdIf + " 1FFFFFFF##0" +
              std::string(24, 'A')) == 0);
  ReceivedFrame got = next_data(rx);
  CHECK(got.is_fd);
  CHECK(same_fd_frame(got.fd_frame, to_fd_frame(got.frame, CANFD_BRS)));
  CHECK(hex(got.frame) == "DEADBEEF01020304");
  got = next_data(rx);
  CHECK(got.is_fd);
  CHECK(got.fd_frame.can_id == (0x1FFFFFFF | CAN_EFF_FLAG));
  CHECK(got.fd_frame.len == 12);
  CHECK((got.fd_flags & CANFD_BRS) == 0);

  Child candump({"stdbuf", "-oL", "candump", "-L", kFdIf});
  CanSocket tx = CanSocket::open(kFdIf, fd_options(send_only()));
  const canfd_frame marker = fd_frame(0x7F0, 0, 1, 0);
  std::string line;
  bool listening = false;
  for (int i = 0; i < 100 && !listening; ++i) {
    tx.send(marker);
    while (candump.read_line(&line, 50)) {
      if (line.find(" " + kFdIf + " 7F0#") != std::string::npos) listening = true;
    }
  }
  REQUIRE(listening);
  std::vector<canfd_frame> frames = fd_traffic(10);
  frames.push_back(fd_frame(0x101, CANFD_BRS, 64, 5));
  frames.push_back(fd_frame(0x1ABCDEF | CAN_EFF_FLAG, CANFD_BRS | CANFD_ESI, 20, 6));
  for (const canfd_frame& f : frames) REQUIRE(tx.send(f) == SendResult::kSent);
  std::size_t matched = 0;
  while (matched < frames.size() && candump.read_line(&line, kTimeoutMs)) {
    if (line.find(" " + kFdIf + " 7F0#") != std::string::npos) continue;  // late marker copies
    INFO(line);
    const auto rec = parse_candump_line(line);
    REQUIRE(rec);
    REQUIRE(rec->is_fd);
    CHECK(rec->interface == kFdIf);
    CHECK(same_fd_frame(rec->fd_frame, frames[matched]));
    // our writer gives the same text for the frame as received (with any flag the kernel added)
    canfd_frame expected = frames[matched];
    expected.flags = static_cast<uint8_t>(expected.flags | (rec->fd_frame.flags & CANFD_FDF));
    CHECK(line == format_candump_line(expected, rec->time_ns, kFdIf));
    ++matched;
  }
  CHECK(matched == frames.size());
}

TEST_CASE("a CAN FD candump log written by CandumpWriter is replayed by canplayer identically",
          "[vcan][fd][can-utils]") {
  ensure_fd_interface();
  const std::string path = temp_path("rig_canplayer_fd") + ".log";
  std::vector<canfd_frame> frames = fd_traffic(8);
  frames.push_back(fd_frame(0x102, CANFD_BRS, 48, 11));
  const can_frame classical = traffic(1)[0];
  {
    CandumpWriter writer(path);
    int64_t t = realtime_ns();
    for (const canfd_frame& f : frames) {
      REQUIRE(writer.write(f, t, kFdIf));
      t += 1000000;  // 1 ms apart
    }
    REQUIRE(writer.write(classical, t, kFdIf));  // a mixed log
    REQUIRE(writer.flush());
  }
  CanSocket rx = CanSocket::open(kFdIf, fd_options(receive_all()));
  REQUIRE(run("canplayer -I " + path + " " + kFdIf + "=" + kFdIf) == 0);
  CommandDecoder cdec;
  for (const canfd_frame& f : frames) {
    const ReceivedFrame got = next_data(rx);
    REQUIRE(got.is_fd);
    CHECK(same_fd_frame(got.fd_frame, f));
    if (got.frame.can_id == kCmdFlap.id || got.frame.can_id == kCmdServo.id) {
      actuator_command_t c;
      cdec.decode(got.frame, &c);
    }
  }
  const ReceivedFrame got = next_data(rx);
  CHECK_FALSE(got.is_fd);
  CHECK(same_frame(got.frame, classical));
  CHECK(nothing_pending(rx, 100));
  CHECK(cdec.stats().messages == 8);
  CHECK(cdec.stats().wrong_length == 1);  // the 48-byte frame
  std::filesystem::remove(path);
}
