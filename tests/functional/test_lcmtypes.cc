// Functional tests of the rig's LCM message contract (lcmtypes/*.lcm, package nimble):
// encode/decode round trips, malformed-message detection and in-process publish/subscribe.

#include <catch2/catch.hpp>

#include <lcm/lcm-cpp.hpp>

#include <nimble/rig_message_list.hpp>

#include <cstddef>
#include <cstdint>
#include <set>
#include <string>
#include <type_traits>
#include <vector>

#include "contract/channels.h"
#include "contract/decode.h"
#include "../support/lcm_samples.h"

using namespace nimble::contract::channels;

namespace {

using namespace rig_test;

// The first channel of the contract (contract/channels.h) that carries type T.
template <typename T>
std::string channel_of() {
  for (const auto& c : nimble::contract::channel_table()) {
    if (c.type == T::getTypeName()) return c.name;
  }
  FAIL("no channel carries " << T::getTypeName());
  return "";
}

template <typename T>
T make_sample() {
  T m{};
  Distinct g;
  fill(m, g);
  return m;
}

template <typename T>
std::vector<uint8_t> encode(const T& m) {
  const int size = m.getEncodedSize();
  REQUIRE(size > 8);
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  REQUIRE(m.encode(buf.data(), 0, size) == size);
  return buf;
}

template <typename T>
class Receiver {
 public:
  void on_message(const lcm::ReceiveBuffer* rbuf, const std::string& channel, const T* msg) {
    ++count;
    last_channel = channel;
    last_size = rbuf->data_size;
    last = *msg;
  }
  int count = 0;
  std::string last_channel;
  uint32_t last_size = 0;
  T last{};
};

}  // namespace

// Every type of lcmtypes/ (the generated list, nimble/rig_message_list.hpp).
#define RIG_LCM_TYPES NIMBLE_RIG_MESSAGE_TYPES

TEMPLATE_TEST_CASE("encode and decode preserve every field", "[lcmtypes]", RIG_LCM_TYPES) {
  const TestType in = make_sample<TestType>();
  const std::vector<uint8_t> buf = encode(in);
  const int size = static_cast<int>(buf.size());

  TestType out{};
  REQUIRE(out.decode(buf.data(), 0, size) == size);
  require_equal(in, out);

  // Same bytes at a non-zero offset.
  std::vector<uint8_t> shifted(buf.size() + 5, 0xEE);
  REQUIRE(in.encode(shifted.data(), 5, size) == size);
  TestType out2{};
  REQUIRE(out2.decode(shifted.data(), 5, size) == size);
  require_equal(in, out2);
}

TEMPLATE_TEST_CASE("encoding into a too small buffer fails", "[lcmtypes]", RIG_LCM_TYPES) {
  const TestType in = make_sample<TestType>();
  const int size = in.getEncodedSize();
  std::vector<uint8_t> buf(static_cast<std::size_t>(size));
  REQUIRE(in.encode(buf.data(), 0, size - 1) < 0);
}

TEMPLATE_TEST_CASE("decoding a truncated buffer fails", "[lcmtypes]", RIG_LCM_TYPES) {
  const std::vector<uint8_t> buf = encode(make_sample<TestType>());
  for (int len = 0; len < static_cast<int>(buf.size()); ++len) {
    INFO("truncated to " << len << " of " << buf.size() << " bytes");
    TestType out{};
    REQUIRE(out.decode(buf.data(), 0, len) < 0);
  }
}

TEMPLATE_TEST_CASE("decoding with a corrupted fingerprint fails", "[lcmtypes]", RIG_LCM_TYPES) {
  const std::vector<uint8_t> buf = encode(make_sample<TestType>());
  const int size = static_cast<int>(buf.size());
  for (std::size_t i = 0; i < 8; ++i) {  // the fingerprint is the first 8 bytes
    INFO("fingerprint byte " << i << " corrupted");
    std::vector<uint8_t> bad = buf;
    bad[i] = static_cast<uint8_t>(bad[i] ^ 0x01);
    TestType out{};
    REQUIRE(out.decode(bad.data(), 0, size) < 0);
  }
}

TEMPLATE_TEST_CASE("decoding a message of another type fails", "[lcmtypes]", RIG_LCM_TYPES) {
  using Other = typename std::conditional<std::is_same<TestType, nimble::heartbeat_t>::value, nimble::fault_event_t,
                                          nimble::heartbeat_t>::type;
  const std::vector<uint8_t> buf = encode(make_sample<Other>());
  TestType out{};
  REQUIRE(out.decode(buf.data(), 0, static_cast<int>(buf.size())) < 0);
}

TEMPLATE_TEST_CASE("publish and receive over memq://", "[lcmtypes][memq]", RIG_LCM_TYPES) {
  lcm::LCM lcm("memq://");
  REQUIRE(lcm.good());

  const std::string channel = channel_of<TestType>();
  Receiver<TestType> receiver;
  lcm::Subscription* sub = lcm.subscribe(channel, &Receiver<TestType>::on_message, &receiver);
  REQUIRE(sub != nullptr);

  const TestType in = make_sample<TestType>();
  REQUIRE(lcm.publish(channel, &in) == 0);
  REQUIRE(lcm.handleTimeout(100) > 0);

  REQUIRE(receiver.count == 1);
  REQUIRE(receiver.last_channel == channel);
  REQUIRE(static_cast<int>(receiver.last_size) == in.getEncodedSize());
  require_equal(in, receiver.last);

  REQUIRE(lcm.unsubscribe(sub) == 0);
}

TEMPLATE_TEST_CASE("utime and seq are the first fields", "[lcmtypes]", RIG_LCM_TYPES) {
  // Encoded layout: 8-byte fingerprint, then utime and seq as big-endian int64.
  const TestType in = make_sample<TestType>();
  const std::vector<uint8_t> buf = encode(in);
  auto be64 = [&buf](std::size_t offset) {
    uint64_t v = 0;
    for (std::size_t i = 0; i < 8; ++i) v = (v << 8) | buf[offset + i];
    return static_cast<int64_t>(v);
  };
  REQUIRE(be64(8) == in.utime);
  REQUIRE(be64(16) == in.seq);
}

TEST_CASE("timing_health_t with zero channels round-trips", "[lcmtypes]") {
  nimble::timing_health_t in{};
  Distinct g;
  fill(in, g, 0);
  const std::vector<uint8_t> buf = encode(in);
  nimble::timing_health_t out{};
  REQUIRE(out.decode(buf.data(), 0, static_cast<int>(buf.size())) == static_cast<int>(buf.size()));
  require_equal(in, out);
  REQUIRE(out.channel.empty());
}

TEMPLATE_TEST_CASE("decode_exact takes every message the encoder writes", "[lcmtypes][decode]", RIG_LCM_TYPES) {
  const TestType in = make_sample<TestType>();
  const std::vector<uint8_t> buf = encode(in);
  TestType out{};
  std::string error;
  CHECK(nimble::contract::decode_exact(buf.data(), static_cast<int>(buf.size()), out, &error));
  CHECK(error.empty());
  require_equal(in, out);
}

namespace {

/// Puts `count` as the big-endian int32 at `pos` of `buf`.
void put_count(std::vector<uint8_t>& buf, std::size_t pos, uint32_t count) {
  for (int i = 0; i < 4; ++i) buf[pos + static_cast<std::size_t>(i)] = static_cast<uint8_t>(count >> (24 - 8 * i));
}

/// Neither LCM's decoder (with the rig's checks) nor decode_exact() takes `buf` as a T.
template <typename T>
void require_count_refused(const std::vector<uint8_t>& buf) {
  T raw{};
  CHECK(raw.decode(buf.data(), 0, static_cast<int>(buf.size())) < 0);
  T out{};
  CHECK_FALSE(nimble::contract::decode_exact(buf.data(), static_cast<int>(buf.size()), out));
}

}  // namespace

TEST_CASE("an array count larger than the message is refused without allocating it", "[lcmtypes][decode]") {
  // Found by the node fuzz targets: LCM's decoders resized an array to the count in the bytes
  // before reading it, and a 200-byte TIMING_HEALTH with num_channels near 2^31 allocated
  // tens of gigabytes (cmake/LcmDecodeChecks.cmake adds the check). The count sits just before
  // the elements, which end the encoding (TIMING_HEALTH: but for an empty stage list).
  for (int n : {0, 1, 3}) {
    INFO(n << " elements");
    nimble::run_control_t rc{};
    Distinct g;
    fill(rc, g);
    rc.participants.assign(static_cast<std::size_t>(n), "plant");
    rc.num_participants = n;
    std::vector<uint8_t> buf = encode(rc);
    const std::size_t rc_count_pos = buf.size() - static_cast<std::size_t>(n) * (4 + 6) - 4;
    for (uint32_t bad : {0x7FFFFFFFu, 1000u, 0xFFFFFFFFu}) {
      std::vector<uint8_t> patched = buf;
      put_count(patched, rc_count_pos, bad);
      require_count_refused<nimble::run_control_t>(patched);
    }

    nimble::timing_health_t th{};
    fill(th, g, n);
    for (auto& c : th.channel) c = kTruth;
    // No stages: the channels' elements are followed by num_stages (0) alone.
    th.num_stages = 0;
    th.stage.clear();
    th.stage_count.clear();
    th.stage_p50_us.clear();
    th.stage_p99_us.clear();
    th.stage_max_us.clear();
    buf = encode(th);
    const std::size_t th_count_pos = buf.size() - 4 - static_cast<std::size_t>(n) * (4 + kTruth.size() + 1 + 5 * 8) - 4;
    for (uint32_t bad : {0x7FFFFFFFu, 1000u, 0xFFFFFFFFu}) {
      std::vector<uint8_t> patched = buf;
      put_count(patched, th_count_pos, bad);
      require_count_refused<nimble::timing_health_t>(patched);
    }
  }
}

TEST_CASE("a string length below 1 is refused", "[lcmtypes][decode]") {
  // Found by the node fuzz targets: a length of INT32_MIN made `length - 1` in LCM's decoder
  // overflow (undefined behaviour, in practice a 2 GB read); 0 made it throw.
  nimble::heartbeat_t hb{};
  hb.process = "plant";
  hb.config_digest = "d";
  const std::vector<uint8_t> buf = encode(hb);
  for (uint32_t length : {0x80000000u, 0u, 0xFFFFFFFFu}) {
    INFO("length " << length);
    std::vector<uint8_t> bad = buf;
    put_count(bad, 24, length);  // process: after fingerprint, utime and seq
    nimble::heartbeat_t raw{};
    CHECK(raw.decode(bad.data(), 0, static_cast<int>(bad.size())) < 0);
  }
}

TEST_CASE("decode_exact refuses a string the encoder cannot write back", "[lcmtypes][decode]") {
  // Found by fuzz_lcm_decode: LCM's decoder takes a string with a NUL inside, or with another
  // byte where its NUL belongs; the encoder (strlen) cannot write such a message again.
  nimble::fault_event_t fault{};
  fault.process = "plant";
  fault.channel = "C";
  fault.message = "abcdef";
  const std::vector<uint8_t> buf = encode(fault);
  const std::size_t message_end = buf.size() - 1;  // the message is the last field: its NUL ends the bytes
  REQUIRE(buf[message_end] == 0);
  for (const auto& [pos, byte] :
       std::vector<std::pair<std::size_t, uint8_t>>{{message_end - 3, 0}, {message_end, 'x'}}) {
    INFO("byte " << pos << " set to " << int{byte});
    std::vector<uint8_t> bad = buf;
    bad[pos] = byte;
    nimble::fault_event_t raw{};
    REQUIRE(raw.decode(bad.data(), 0, static_cast<int>(bad.size())) == static_cast<int>(bad.size()));  // LCM takes it
    nimble::fault_event_t out{};
    std::string error;
    CHECK_FALSE(nimble::contract::decode_exact(bad.data(), static_cast<int>(bad.size()), out, &error));
    CHECK(error.find("NUL") != std::string::npos);
  }
}

TEST_CASE("every type has its own fingerprint", "[lcmtypes]") {
  std::vector<int64_t> hashes;
  nimble::for_each_message_type([&hashes](auto type) { hashes.push_back(decltype(type)::type::getHash()); });
  const std::set<int64_t> unique(hashes.begin(), hashes.end());
  REQUIRE(hashes.size() == static_cast<std::size_t>(nimble::kRigMessageCount));
  REQUIRE(unique.size() == hashes.size());
}

TEST_CASE("enumeration constants have their documented values", "[lcmtypes]") {
  using nimble::actuator_command_t;
  using nimble::controller_status_t;
  using nimble::fault_event_t;
  using nimble::heartbeat_t;
  using nimble::imu_sample_t;

  CHECK(actuator_command_t::MODE_LEFT_RIGHT == 0);
  CHECK(actuator_command_t::MODE_DELTA_F == 1);

  CHECK(controller_status_t::INPUT_TRUTH == 0);
  CHECK(controller_status_t::INPUT_ESTIMATE == 1);

  CHECK(imu_sample_t::SAT_GYRO_X == 1);
  CHECK(imu_sample_t::SAT_GYRO_Y == 2);
  CHECK(imu_sample_t::SAT_GYRO_Z == 4);
  CHECK(imu_sample_t::SAT_ACCEL_X == 8);
  CHECK(imu_sample_t::SAT_ACCEL_Y == 16);
  CHECK(imu_sample_t::SAT_ACCEL_Z == 32);

  CHECK(heartbeat_t::STATE_STARTING == 0);
  CHECK(heartbeat_t::STATE_READY == 1);
  CHECK(heartbeat_t::STATE_RUNNING == 2);
  CHECK(heartbeat_t::STATE_STOPPING == 3);
  CHECK(heartbeat_t::STATE_FAULT == 4);
  CHECK(heartbeat_t::STATE_FINISHED == 5);

  CHECK(fault_event_t::SEVERITY_INFO == 0);
  CHECK(fault_event_t::SEVERITY_WARNING == 1);
  CHECK(fault_event_t::SEVERITY_ERROR == 2);
  CHECK(fault_event_t::SEVERITY_FATAL == 3);

  CHECK(fault_event_t::CODE_OTHER == 0);
  CHECK(fault_event_t::CODE_COMMAND_TIMEOUT == 1);
  CHECK(fault_event_t::CODE_MESSAGE_MALFORMED == 2);
  CHECK(fault_event_t::CODE_QUEUE_DROP == 3);
  CHECK(fault_event_t::CODE_DEADLINE_MISS == 4);
  CHECK(fault_event_t::CODE_PROCESS_EXIT == 5);
  CHECK(fault_event_t::CODE_CAN_ERROR_FRAME == 6);
  CHECK(fault_event_t::CODE_CONFIG_ERROR == 7);
  CHECK(fault_event_t::CODE_ESTIMATOR_DIVERGED == 8);
  CHECK(fault_event_t::CODE_HEARTBEAT_LOST == 9);
  CHECK(fault_event_t::CODE_STEP_ACK_TIMEOUT == 10);
  CHECK(fault_event_t::CODE_TRACKING_LOST == 11);
  CHECK(fault_event_t::CODE_REALTIME_UNAVAILABLE == 12);
  CHECK(fault_event_t::CODE_COMMAND_CLAMPED == 13);
  CHECK(fault_event_t::CODE_INPUT_STALE == 14);
  CHECK(fault_event_t::CODE_MEASUREMENT_OUT_OF_WINDOW == 15);
}
