/// bus_flood: publishes garbage on the rig's channels, to test that a run survives it.
///
///   bus_flood [--url URL] [--rate HZ] [--seconds S] [--burst N] [--seed N] [--max-bytes N]
///
/// Publishes through liblcm, like any process that joined the run's network, at `rate`
/// messages per second for `seconds` (default 2000/s for 2 s), or, with --burst N, N messages
/// as fast as it can once per second. Each message goes to one of the rig's channels drawn at
/// random, with a payload of 0 to --max-bytes (default 600) random bytes (LCM fragments those
/// over about 64 KB); half of the payloads start with the channel's
/// real 8-byte LCM fingerprint, so that they reach the decoder's field parsing; some of those
/// carry a string length of 0 where the type has its first string (the input that makes
/// LCM 1.3.1's decoders throw). Prints how many it sent. Used by the `fault` system tests with
/// `nsenter -t <rig pid> -n`.

#include <time.h>

#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include <lcm/lcm.h>
#include <nimble/rig_message_list.hpp>

#include "cmdline/args.h"
#include "contract/channels.h"

namespace {

int64_t now_ns() {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<int64_t>(ts.tv_sec) * 1000000000LL + ts.tv_nsec;
}

void sleep_until(int64_t t_ns) {
  const timespec ts{static_cast<time_t>(t_ns / 1000000000LL), static_cast<long>(t_ns % 1000000000LL)};
  clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &ts, nullptr);
}

/// The 8-byte fingerprint messages of `channel`'s type start with (the type from the channel
/// table, contract/channels.h; its hash from the generated list of types): big-endian, as LCM
/// encodes it.
std::vector<unsigned char> fingerprint(const std::string& channel) {
  const nimble::contract::ChannelSpec* spec = nimble::contract::find_channel(channel);
  uint64_t hash = 0;
  if (spec == nullptr || !nimble::with_message_type(spec->type, [&hash](auto type) {
        hash = static_cast<uint64_t>(decltype(type)::type::getHash());
      })) {
    std::fprintf(stderr, "bus_flood: channel %s has no message type\n", channel.c_str());
    std::exit(1);
  }
  std::vector<unsigned char> b(8);
  for (int i = 0; i < 8; ++i) b[static_cast<std::size_t>(i)] = static_cast<unsigned char>(hash >> (56 - 8 * i));
  return b;
}

}  // namespace

int main(int argc, char** argv) {
  std::string url = "udpm://239.255.76.67:7667?ttl=0";
  double rate = 2000.0, seconds = 2.0;
  long burst = 0;
  std::size_t max_bytes = 600;
  unsigned long seed = 1;
  nimble::cmdline::CommandLine cl(
      "bus_flood",
      "Publishes garbage on the rig's channels through liblcm, to test that a run survives it: each\n"
      "message goes to one of the rig's channels drawn at random, with 0 to --max-bytes random bytes,\n"
      "half of them behind the channel type's real fingerprint. Prints how many it sent.");
  cl->add_option("--url", url, "the LCM URL to publish on")->type_name("URL")->capture_default_str();
  cl->add_option("--rate", rate, "messages per second (without --burst)")
      ->check(nimble::cmdline::kFinite & CLI::Range(1e-3, 1e9))
      ->type_name("HZ")
      ->capture_default_str();
  cl->add_option("--seconds", seconds, "how long it floods")
      ->check(nimble::cmdline::kFinite & CLI::Range(0.0, 1e6))
      ->type_name("S")
      ->capture_default_str();
  cl->add_option("--burst", burst, "N messages as fast as it can once per second instead of --rate (0: off)")
      ->check(nimble::cmdline::kWholeNumber)
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--seed", seed, "the seed of the random choices")
      ->check(nimble::cmdline::kWholeNumber)
      ->type_name("N")
      ->capture_default_str();
  cl->add_option("--max-bytes", max_bytes, "the longest payload (LCM fragments those over about 64 KB)")
      ->check(CLI::Range(std::size_t{0}, std::size_t{1} << 26))
      ->type_name("N")
      ->capture_default_str();
  if (const auto done = cl.parse(argc, argv)) return *done;
  namespace ch = nimble::contract::channels;
  struct Target {
    std::string channel;
    std::vector<unsigned char> fingerprint;
    int first_string_offset;  ///< byte offset of the first string's length, -1 if none
  };
  const std::vector<Target> targets = {
      {ch::kTruth, fingerprint(ch::kTruth), -1},
      {ch::kImu, fingerprint(ch::kImu), -1},
      {ch::kMocapPose, fingerprint(ch::kMocapPose), -1},
      {ch::kEstimate, fingerprint(ch::kEstimate), -1},
      {ch::kActuatorCommand, fingerprint(ch::kActuatorCommand), -1},
      {ch::kActuatorFeedback, fingerprint(ch::kActuatorFeedback), -1},
      {ch::kAttitudeSetpoint, fingerprint(ch::kAttitudeSetpoint), -1},
      {ch::kControllerStatus, fingerprint(ch::kControllerStatus), -1},
      {ch::kHeartbeat, fingerprint(ch::kHeartbeat), 24},
      {ch::kTimingHealth, fingerprint(ch::kTimingHealth), 24},
      {ch::kFault, fingerprint(ch::kFault), 24},
      {ch::kRunControl, fingerprint(ch::kRunControl), -1},
  };
  lcm_t* lcm = lcm_create(url.c_str());
  if (lcm == nullptr) {
    std::fprintf(stderr, "bus_flood: LCM does not start on %s\n", url.c_str());
    return 1;
  }
  std::mt19937_64 rng(seed);
  const auto send_one = [&] {
    const Target& t = targets[rng() % targets.size()];
    std::vector<unsigned char> payload(rng() % (max_bytes + 1));
    for (auto& b : payload) b = static_cast<unsigned char>(rng());
    if (rng() % 2 == 0 && payload.size() >= 8) {
      std::copy(t.fingerprint.begin(), t.fingerprint.end(), payload.begin());
      if (t.first_string_offset > 0 && payload.size() >= static_cast<std::size_t>(t.first_string_offset + 4) &&
          rng() % 4 == 0) {
        std::memset(payload.data() + t.first_string_offset, 0, 4);
      }
    }
    lcm_publish(lcm, t.channel.c_str(), payload.data(), static_cast<unsigned>(payload.size()));
  };
  long sent = 0;
  const int64_t start = now_ns(), end = start + static_cast<int64_t>(seconds * 1e9);
  if (burst > 0) {
    for (int64_t second = start; second < end; second += 1000000000LL) {
      sleep_until(second);  // between bursts the flood sleeps: the load is the messages only
      for (long k = 0; k < burst; ++k, ++sent) send_one();
    }
  } else {
    const int64_t period = static_cast<int64_t>(1e9 / rate);
    for (int64_t next = start; next < end; next += period, ++sent) {
      sleep_until(next);
      send_one();
    }
  }
  lcm_destroy(lcm);
  std::printf("bus_flood: sent %ld messages on %zu channels\n", sent, targets.size());
  return 0;
}
