#pragma once
/// Mathematical constants of the rig, defined once (C++17 has no std::numbers).

namespace nimble {

inline constexpr double kPi = 3.14159265358979323846;

}  // namespace nimble
