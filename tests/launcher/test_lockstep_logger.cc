// LockstepLogger (launcher/lockstep_logger.h): the ticks it answers, and when the launcher may
// read the run's messages late because the next tick is not one it must answer.

#include <string>
#include <vector>

#include <catch2/catch.hpp>
#include <nimble/rig_clock_t.hpp>
#include <nimble/step_ack_t.hpp>

#include "contract/channels.h"
#include "launcher/lockstep_logger.h"
#include "tests/support/encoded.h"

using nimble::launcher::LockstepLogger;
namespace ch = nimble::contract::channels;

namespace {

std::vector<unsigned char> encode_tick(int64_t step, int64_t t_ns) {
  nimble::rig_clock_t tick{};
  tick.step = step;
  tick.sim_time_ns = t_ns;
  tick.utime = t_ns / 1000;
  tick.dt_ns = 1000000;
  return nimble::test::encoded(tick);
}

std::vector<unsigned char> encode_ack(const std::string& process, int64_t step, int64_t next_due_ns) {
  nimble::step_ack_t ack{};
  ack.step = step;
  ack.next_due_ns = next_due_ns;
  ack.process = process;
  return nimble::test::encoded(ack);
}

}  // namespace

TEST_CASE("lockstep logger: answers the ticks it is due at, and knows when the next tick is not its own",
          "[launcher]") {
  std::vector<nimble::step_ack_t> sent;
  LockstepLogger logger(10000000, [&](const nimble::step_ack_t& a) { sent.push_back(a); });  // every 10 ms
  // Before any other participant answered: the next tick may be its own.
  CHECK(logger.may_be_due_next());

  auto tick = [&](int64_t step) {
    const auto b = encode_tick(step, step * 1000000);
    logger.on_message(ch::kRigClock, b.data(), static_cast<int>(b.size()));
  };
  auto ack = [&](const std::string& who, int64_t step, int64_t next_due_ms) {
    const auto b = encode_ack(who, step, next_due_ms * 1000000);
    logger.on_message(ch::kStepAck, b.data(), static_cast<int>(b.size()));
  };

  tick(0);  // due at 0: answered, next due at 10 ms
  REQUIRE(sent.size() == 1);
  CHECK(sent[0].step == 0);
  CHECK(sent[0].next_due_ns == 10000000);
  CHECK(sent[0].process == LockstepLogger::kName);
  // The others are due at 2 and 5 ms: the next tick is theirs.
  ack("estimator", 0, 2);
  ack("mocap", 0, 5);
  CHECK_FALSE(logger.may_be_due_next());
  for (int64_t s = 1; s < 10; ++s) tick(s);  // not due: nothing answered
  CHECK(sent.size() == 1);
  // Its own acknowledgement on the bus does not count as another participant's.
  const auto own = encode_ack(LockstepLogger::kName, 0, 10);
  logger.on_message(ch::kStepAck, own.data(), static_cast<int>(own.size()));
  CHECK_FALSE(logger.may_be_due_next());
  // Once every other participant is due at or after 10 ms, the next tick is (also) its own.
  ack("estimator", 8, 12);
  CHECK_FALSE(logger.may_be_due_next());  // mocap is still due at 5 ms
  ack("mocap", 5, 10);
  CHECK(logger.may_be_due_next());
  tick(10);
  REQUIRE(sent.size() == 2);
  CHECK(sent[1].step == 10);
  CHECK(sent[1].next_due_ns == 20000000);
  CHECK(sent[1].seq == sent[0].seq + 1);
  CHECK_FALSE(logger.may_be_due_next());

  // A tick that does not decode is neither answered nor counted.
  const std::vector<unsigned char> garbage(5, 0xff);
  logger.on_message(ch::kRigClock, garbage.data(), static_cast<int>(garbage.size()));
  CHECK(sent.size() == 2);
}
