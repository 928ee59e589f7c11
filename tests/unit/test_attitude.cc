// Unit tests of the attitude conversions (core/attitude.h) and the chi-square functions.

#include <cmath>
#include <random>

#include <catch2/catch.hpp>

#include "core/attitude.h"
#include "core/chi_square.h"

using namespace nimble;

namespace {

double rotation_distance_rad(const Eigen::Matrix3d& A, const Eigen::Matrix3d& B) {
  return quaternion_log(quaternion_from_rotation(A.transpose() * B)).norm();
}

}  // namespace

TEST_CASE("Euler -> quaternion -> Euler round trip over random attitudes", "[attitude]") {
  std::mt19937_64 rng(42);
  std::uniform_real_distribution<double> angle(-M_PI, M_PI);
  std::uniform_real_distribution<double> pitch(-85.0 * M_PI / 180.0, 85.0 * M_PI / 180.0);
  double worst = 0.0;
  for (int i = 0; i < 20000; ++i) {
    const Eigen::Vector3d euler(angle(rng), pitch(rng), angle(rng));
    const Eigen::Quaterniond q = quaternion_from_euler_zyx(euler);
    REQUIRE(q.norm() == Approx(1.0).margin(1e-14));
    REQUIRE(q.w() >= 0.0);
    const Eigen::Vector3d back = euler_zyx_from_quaternion(q);
    for (int k = 0; k < 3; ++k) worst = std::max(worst, std::fabs(wrap_angle_rad(back[k] - euler[k])));
    // The matrix and quaternion routes agree.
    REQUIRE((rotation_from_euler_zyx(euler) - q.toRotationMatrix()).cwiseAbs().maxCoeff() < 1e-14);
  }
  INFO("largest round-trip angle error " << worst << " rad");
  CHECK(worst < 1e-12);
}

TEST_CASE("rotation -> quaternion -> rotation and exp/log round trips", "[attitude]") {
  std::mt19937_64 rng(7);
  std::normal_distribution<double> normal(0.0, 1.0);
  for (int i = 0; i < 5000; ++i) {
    Eigen::Vector3d rv(normal(rng), normal(rng), normal(rng));
    if (rv.norm() > 3.1) rv *= 3.1 / rv.norm();
    const Eigen::Quaterniond q = quaternion_exp(rv);
    REQUIRE((quaternion_log(q) - rv).norm() < 1e-12);
    const Eigen::Matrix3d R = q.toRotationMatrix();
    REQUIRE(rotation_distance_rad(quaternion_from_rotation(R).toRotationMatrix(), R) < 1e-12);
    const std::array<double, 4> wire = quaternion_to_wxyz(q);
    REQUIRE(quaternion_from_wxyz(wire).angularDistance(q) < 1e-12);
    // Euler route (also through gimbal lock, where only the rotation is unique).
    REQUIRE(rotation_distance_rad(rotation_from_euler_zyx(euler_zyx_from_rotation(R)), R) < 1e-9);
  }
}

TEST_CASE("known attitudes follow the rig conventions (NED, body x fwd y right z down, ZYX)", "[attitude]") {
  const double d = M_PI / 180.0;
  SECTION("identity") {
    CHECK(euler_zyx_from_quaternion(Eigen::Quaterniond::Identity()).norm() == Approx(0.0).margin(1e-15));
  }
  SECTION("roll 30 deg right wing down: body y axis points east and down") {
    const Eigen::Matrix3d R = rotation_from_euler_zyx(Eigen::Vector3d(30 * d, 0, 0));
    const Eigen::Vector3d y_world = R * Eigen::Vector3d::UnitY();
    CHECK(y_world.x() == Approx(0.0).margin(1e-15));
    CHECK(y_world.y() == Approx(std::cos(30 * d)));
    CHECK(y_world.z() == Approx(std::sin(30 * d)));  // down is positive
  }
  SECTION("pitch 20 deg nose up: body x axis points north and up") {
    const Eigen::Vector3d x_world = rotation_from_euler_zyx(Eigen::Vector3d(0, 20 * d, 0)) * Eigen::Vector3d::UnitX();
    CHECK(x_world.x() == Approx(std::cos(20 * d)));
    CHECK(x_world.z() == Approx(-std::sin(20 * d)));
  }
  SECTION("yaw 90 deg: nose points east") {
    const Eigen::Vector3d x_world = rotation_from_euler_zyx(Eigen::Vector3d(0, 0, 90 * d)) * Eigen::Vector3d::UnitX();
    CHECK(x_world.y() == Approx(1.0));
  }
  SECTION("quaternion of a pure roll is [cos(phi/2), sin(phi/2), 0, 0] in wire order") {
    const auto wire = quaternion_to_wxyz(quaternion_from_euler_zyx(Eigen::Vector3d(40 * d, 0, 0)));
    CHECK(wire[0] == Approx(std::cos(20 * d)));
    CHECK(wire[1] == Approx(std::sin(20 * d)));
    CHECK(wire[2] == Approx(0.0).margin(1e-15));
    CHECK(wire[3] == Approx(0.0).margin(1e-15));
  }
  SECTION("yaw, pitch and roll compose in ZYX order") {
    const Eigen::Vector3d e(10 * d, -25 * d, 135 * d);
    const Eigen::Matrix3d expected =
        (Eigen::AngleAxisd(e[2], Eigen::Vector3d::UnitZ()) * Eigen::AngleAxisd(e[1], Eigen::Vector3d::UnitY()) *
         Eigen::AngleAxisd(e[0], Eigen::Vector3d::UnitX()))
            .toRotationMatrix();
    CHECK((rotation_from_euler_zyx(e) - expected).cwiseAbs().maxCoeff() < 1e-15);
  }
  SECTION("gravity in body axes at rest: specific force (0, 0, -g) when level") {
    const Eigen::Matrix3d R = rotation_from_euler_zyx(Eigen::Vector3d::Zero());
    const Eigen::Vector3d f_body = -(R.transpose() * Eigen::Vector3d(0, 0, 9.81));
    CHECK(f_body.z() == Approx(-9.81));
  }
}

TEST_CASE("gimbal lock: phi set to 0, rotation reproduced", "[attitude]") {
  for (const double theta : {M_PI / 2, -M_PI / 2}) {
    for (const double phi : {-1.0, 0.0, 0.3, 2.5}) {
      for (const double psi : {-2.0, 0.0, 0.5, 3.0}) {
        const Eigen::Matrix3d R = rotation_from_euler_zyx(Eigen::Vector3d(phi, theta, psi));
        const Eigen::Vector3d e = euler_zyx_from_rotation(R);
        CHECK(e[0] == 0.0);
        CHECK(e[1] == Approx(theta).margin(1e-7));
        CHECK(rotation_distance_rad(rotation_from_euler_zyx(e), R) < 1e-7);
        // Outside the threshold band the normal formulas are used; the result is still the rotation.
        const Eigen::Matrix3d R_near = rotation_from_euler_zyx(Eigen::Vector3d(phi, theta * (1.0 - 1e-5), psi));
        CHECK(rotation_distance_rad(rotation_from_euler_zyx(euler_zyx_from_rotation(R_near)), R_near) < 1e-9);
      }
    }
  }
}

TEST_CASE("wrap_angle_rad maps into -pi (excluded) to pi (included)", "[attitude]") {
  CHECK(wrap_angle_rad(M_PI) == Approx(M_PI));
  CHECK(wrap_angle_rad(-M_PI) == Approx(M_PI));
  CHECK(wrap_angle_rad(3 * M_PI / 2) == Approx(-M_PI / 2));
  CHECK(wrap_angle_rad(-7.0) == Approx(-7.0 + 2 * M_PI));
  CHECK(wrap_angle_rad(0.25) == 0.25);
  CHECK(wrap_angle_rad(1e6) == Approx(std::remainder(1e6, 2 * M_PI)));
}

TEST_CASE("euler_rate_matrix maps body rates to Euler-angle rates", "[attitude]") {
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> u(-1.2, 1.2);
  for (int i = 0; i < 200; ++i) {
    const Eigen::Vector3d e(u(rng), u(rng), u(rng));
    const Eigen::Vector3d w(u(rng), u(rng), u(rng));
    // Rotate by omega dt in body axes and difference the Euler angles.
    const double dt = 1e-6;
    const Eigen::Quaterniond q = quaternion_from_euler_zyx(e);
    const Eigen::Vector3d ep = euler_zyx_from_quaternion(q * quaternion_exp(w * dt));
    const Eigen::Vector3d em = euler_zyx_from_quaternion(q * quaternion_exp(-w * dt));
    Eigen::Vector3d numeric;
    for (int k = 0; k < 3; ++k) numeric[k] = wrap_angle_rad(ep[k] - em[k]) / (2 * dt);
    CHECK((euler_rate_matrix(e[0], e[1]) * w - numeric).norm() < 1e-6);
  }
}

TEST_CASE("chi-square quantiles match tabulated values", "[chi_square]") {
  CHECK(chi_square_quantile(0.999, 6) == Approx(22.4577).epsilon(1e-5));
  CHECK(chi_square_quantile(0.999, 3) == Approx(16.2662).epsilon(1e-5));
  CHECK(chi_square_quantile(0.975, 12) == Approx(23.3367).epsilon(1e-5));
  CHECK(chi_square_quantile(0.025, 12) == Approx(4.40379).epsilon(1e-5));
  CHECK(chi_square_quantile(0.5, 1) == Approx(0.454936).epsilon(1e-5));
  CHECK(chi_square_quantile(0.975, 240) == Approx(284.80).epsilon(1e-3));  // Wilson-Hilferty value
  CHECK(chi_square_cdf(chi_square_quantile(0.3, 17.5), 17.5) == Approx(0.3).epsilon(1e-10));
  CHECK_THROWS_AS(chi_square_quantile(1.0, 3), std::invalid_argument);
  CHECK_THROWS_AS(chi_square_quantile(0.5, 0), std::invalid_argument);
}
