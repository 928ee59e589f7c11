// Unit tests: LatchedInput, the lockstep input latch of the controller, estimator and mocap nodes.

#include <cstdint>
#include <vector>

#include <catch2/catch.hpp>

#include "transport/latched_input.h"

using nimble::transport::LatchedInput;
using Latch = LatchedInput<int>;

TEST_CASE("latched input: a tick sees the newest message stamped before it, not one stamped at or after it",
          "[latch]") {
  Latch latch;
  CHECK(latch.newest(1000) == nullptr);
  latch.push(0, 10);     // published at tick 0
  latch.push(1000, 11);  // published at tick 1000, arrived before our tick 1000 ran
  REQUIRE(latch.newest(1000) != nullptr);
  CHECK(*latch.newest(1000) == 10);
  latch.push(2000, 12);  // arrived early, stamped after the tick
  CHECK(*latch.newest(1000) == 10);
  // Next tick: the newest stamped before it, whatever else arrived meanwhile.
  CHECK(*latch.newest(2000) == 11);
  // The one returned stays latched until a newer one is released.
  CHECK(*latch.newest(2000) == 11);
  CHECK(*latch.newest(3000) == 12);
  CHECK(*latch.newest(9000) == 12);
  CHECK(latch.size() == 1);
}

TEST_CASE("latched input: real time gives the newest message pushed, whatever its stamp", "[latch]") {
  Latch latch;
  CHECK(latch.newest(0, false) == nullptr);
  latch.push(0, 1);
  latch.push(5000, 2);
  REQUIRE(latch.newest(1000, false) != nullptr);
  CHECK(*latch.newest(1000, false) == 2);
  CHECK(latch.size() == 1);
}

TEST_CASE("latched input: drain applies the released messages in arrival order and keeps the rest", "[latch]") {
  Latch latch;
  for (int i = 0; i < 5; ++i) latch.push(i * 1000, i);
  std::vector<int> seen;
  CHECK(latch.ready(1000));
  latch.drain(2000, [&](int m) { seen.push_back(m); });
  CHECK(seen == std::vector<int>{0, 1});
  CHECK(latch.front() == 2);
  CHECK(latch.front_stamp_utime() == 2000);
  CHECK_FALSE(latch.ready(2000));
  latch.pop();
  CHECK(latch.front() == 3);
  latch.drain(10000, [&](int m) { seen.push_back(m); });
  CHECK(seen == std::vector<int>{0, 1, 3, 4});
  CHECK(latch.empty());
  CHECK_FALSE(latch.ready(10000));
}

TEST_CASE("latched input: a message due at its stamp goes out at the tick at or after it", "[latch]") {
  Latch latch(Latch::Release::kAtStamp);
  latch.push(4500, 1);
  latch.push(5000, 2);
  latch.push(7500, 3);
  std::vector<int> seen;
  latch.drain(4000, [&](int m) { seen.push_back(m); });
  CHECK(seen.empty());
  latch.drain(5000, [&](int m) { seen.push_back(m); });
  CHECK(seen == std::vector<int>{1, 2});
  CHECK(*latch.newest(7500) == 3);
}

TEST_CASE("latched input: past its capacity the oldest message goes", "[latch]") {
  Latch latch(Latch::Release::kAfterStamp, 2);
  latch.push(0, 1);
  latch.push(1000, 2);
  latch.push(2000, 3);
  CHECK(latch.size() == 2);
  CHECK(latch.newest(1000) == nullptr);  // the message stamped 0 was dropped
  CHECK(*latch.newest(2000) == 2);
}
