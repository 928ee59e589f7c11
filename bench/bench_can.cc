// bench_can: latency of the CAN path on a (virtual) CAN interface, printed as p50 / p99 / max.
//
//   bench_can [--interface vcan0] [--count N] [--warmup N]
//
// Three figures, all in one process on one interface:
//  - frame: one frame send() -> receive() on a second socket;
//  - command: actuator_command_t -> CommandEncoder -> 2 frames -> CommandDecoder -> complete
//    actuator_command_t on a second socket;
//  - round trip: a frame sent, echoed back by a thread with its own socket, received.
// Needs a CAN interface: on a kernel without CAN run it as
//   tools/canvm/canvm run -- build/bin/bench_can

#include <time.h>

#include <algorithm>
#include <atomic>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <exception>
#include <string>
#include <thread>
#include <vector>

#include "can_bridge/can_socket.h"
#include "can_bridge/codec.h"
#include "can_bridge/frame_layout.h"
#include "cmdline/args.h"

namespace {

using namespace nimble::can;

int64_t now_ns(clockid_t clock) {
  timespec ts{};
  clock_gettime(clock, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000 + ts.tv_nsec;
}

struct Summary {
  double p50_us, p99_us, max_us;
  std::size_t n;
};

Summary summarise(std::vector<int64_t> ns) {
  std::sort(ns.begin(), ns.end());
  auto at = [&](double q) {
    const std::size_t i =
        std::min(ns.size() - 1, static_cast<std::size_t>(q * static_cast<double>(ns.size() - 1) + 0.5));
    return static_cast<double>(ns[i]) / 1000.0;
  };
  return {at(0.50), at(0.99), static_cast<double>(ns.back()) / 1000.0, ns.size()};
}

void print(const char* what, const Summary& s) {
  std::printf("  %-44s p50 %8.1f us   p99 %8.1f us   max %8.1f us   (n = %zu)\n", what, s.p50_us, s.p99_us, s.max_us,
              s.n);
}

std::vector<can_filter> only(uint32_t id) { return {can_filter{id, CAN_SFF_MASK | CAN_EFF_FLAG | CAN_RTR_FLAG}}; }

/// Receives until a data frame arrives (error frames are skipped); false on timeout.
bool receive_data(CanSocket& s, ReceivedFrame* rx, int timeout_ms) {
  for (;;) {
    if (s.receive(rx, timeout_ms) != ReceiveResult::kFrame) return false;
    if (!rx->is_error_frame) return true;
  }
}

int run(const std::string& iface, int count, int warmup) {
  CanSocketOptions tx_opt;
  tx_opt.filters = only(kFbMotor.id);
  CanSocketOptions rx_opt;
  rx_opt.filters = {only(kCmdFlap.id)[0], only(kCmdServo.id)[0]};
  CanSocket tx = CanSocket::open(iface, tx_opt);
  CanSocket rx = CanSocket::open(iface, rx_opt);

  std::vector<int64_t> frame_ns, kernel_to_user_ns, command_ns, rtt_ns;
  can_frame probe{};
  probe.can_id = kCmdFlap.id;
  probe.len = 8;

  // 1. one frame, send -> receive
  for (int i = 0; i < warmup + count; ++i) {
    probe.data[0] = static_cast<uint8_t>(i);
    const int64_t t0 = now_ns(CLOCK_MONOTONIC);
    if (tx.send(probe) != SendResult::kSent) throw std::runtime_error("send failed");
    ReceivedFrame got;
    if (!receive_data(rx, &got, 1000)) throw std::runtime_error("frame not received within 1 s");
    const int64_t t1 = now_ns(CLOCK_MONOTONIC);
    const int64_t wall = now_ns(CLOCK_REALTIME);
    if (i >= warmup) {
      frame_ns.push_back(t1 - t0);
      if (got.has_kernel_time) kernel_to_user_ns.push_back(wall - got.kernel_time_ns);
    }
  }

  // 2. command -> frames -> command
  CommandEncoder encoder;
  CommandDecoder decoder;
  nimble::actuator_command_t cmd{};
  cmd.mode = nimble::actuator_command_t::MODE_DELTA_F;
  cmd.flap_freq_collective_radps = 106.8;
  cmd.throttle_pct = 55.0;
  for (int i = 0; i < warmup + count; ++i) {
    cmd.seq = i;
    cmd.rolling_counter = static_cast<int8_t>(i % 16);
    cmd.delta_f_radps = 0.01 * (i % 200) - 1.0;
    cmd.dihedral_rad = 0.001 * (i % 100);
    const int64_t t0 = now_ns(CLOCK_MONOTONIC);
    for (const can_frame& f : encoder.encode(cmd)) {
      if (tx.send(f) != SendResult::kSent) throw std::runtime_error("send failed");
    }
    nimble::actuator_command_t out;
    DecodeResult r = DecodeResult::kAccepted;
    while (r != DecodeResult::kMessageComplete) {
      ReceivedFrame got;
      if (!receive_data(rx, &got, 1000)) throw std::runtime_error("command frames not received within 1 s");
      r = decoder.decode(got.frame, &out);
      if (r != DecodeResult::kAccepted && r != DecodeResult::kMessageComplete) {
        throw std::runtime_error(std::string("decoder: ") + to_string(r));
      }
    }
    const int64_t t1 = now_ns(CLOCK_MONOTONIC);
    if (i >= warmup) command_ns.push_back(t1 - t0);
  }

  // 3. round trip through an echo thread
  std::atomic<bool> stop{false};
  std::thread echo([&] {  // from here on only this thread uses rx
    while (!stop.load()) {
      ReceivedFrame got;
      if (!receive_data(rx, &got, 50)) continue;
      got.frame.can_id = kFbMotor.id;
      rx.send(got.frame);
    }
  });
  for (int i = 0; i < warmup + count; ++i) {
    probe.data[0] = static_cast<uint8_t>(i);
    const int64_t t0 = now_ns(CLOCK_MONOTONIC);
    tx.send(probe);
    ReceivedFrame got;
    if (!receive_data(tx, &got, 1000)) {
      stop = true;
      echo.join();
      throw std::runtime_error("echo not received within 1 s");
    }
    const int64_t t1 = now_ns(CLOCK_MONOTONIC);
    if (i >= warmup) rtt_ns.push_back(t1 - t0);
  }
  stop = true;
  echo.join();

  const char* where = std::getenv("CANVM_GUEST") != nullptr ? "measured inside the qemu VM (software emulation, no KVM)"
                                                            : "measured on this host's kernel";
  std::printf("bench_can on %s, %d samples each after %d warm-up; %s\n", iface.c_str(), count, warmup, where);
  print("frame send -> receive (one frame)", summarise(frame_ns));
  if (!kernel_to_user_ns.empty()) print("  of which kernel rx timestamp -> user space", summarise(kernel_to_user_ns));
  print("command -> 2 frames -> decoded command", summarise(command_ns));
  print("round trip (frame -> echo thread -> frame)", summarise(rtt_ns));
  std::printf("  socket counters: sent %llu, received %llu, ENOBUFS %llu, dropped %llu\n",
              static_cast<unsigned long long>(tx.stats().frames_sent),
              static_cast<unsigned long long>(rx.stats().frames_received + tx.stats().frames_received),
              static_cast<unsigned long long>(tx.stats().send_enobufs),
              static_cast<unsigned long long>(tx.stats().send_dropped + rx.stats().receive_dropped));
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  std::string iface = "vcan0";
  int count = 2000;
  int warmup = 200;
  nimble::cmdline::CommandLine cl(
      "bench_can",
      "Latency of the CAN path on a (virtual) CAN interface, printed as p50 / p99 / max: one frame send ->\n"
      "receive on a second socket; actuator_command_t -> 2 frames -> decoded command; a round trip through\n"
      "an echo thread.");
  cl->footer("Needs a CAN interface; on a kernel without CAN: tools/canvm/canvm run -- build/bin/bench_can");
  cl->add_option("--interface", iface, "the CAN interface")->type_name("IFACE")->capture_default_str();
  cl->add_option("--count", count, "samples of each figure")
      ->check(CLI::Range(1, 10000000))
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--warmup", warmup, "samples sent first and not counted")
      ->check(CLI::Range(0, 10000000))
      ->type_name("N")
      ->capture_default_str();
  if (const auto done = cl.parse(argc, argv)) return *done;
  try {
    return run(iface, count, warmup);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "bench_can: %s\n", e.what());
    return 1;
  }
}
