#pragma once
// A message's LCM bytes as a publisher sends them, for the tests that feed bytes to a handler,
// a recorder or a monitor; the encoder must write them all.

#include <cstddef>
#include <cstdint>
#include <vector>

#include <catch2/catch.hpp>

namespace nimble::test {

template <typename T>
std::vector<std::uint8_t> encoded(const T& m) {
  std::vector<std::uint8_t> out(static_cast<std::size_t>(m.getEncodedSize()));
  REQUIRE(m.encode(out.data(), 0, static_cast<int>(out.size())) == static_cast<int>(out.size()));
  return out;
}

}  // namespace nimble::test
