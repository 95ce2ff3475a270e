#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "systems/incision/port_arc.hpp"
#include "tests/systems/incision/incision_fixture.hpp"

namespace phaco::incision {
namespace {

using test::expect_invalid;

constexpr double kDeg = std::numbers::pi / 180.0;

Vec3 at(double deg, double r = 5.0, double z = 2.5) {
  return {r * std::cos(deg * kDeg), r * std::sin(deg * kDeg), z};
}

double angle_deg(const Eigen::Vector2d& v) {
  return std::atan2(v.y(), v.x()) / kDeg;
}

TEST(PortArc, OpensOnTheShorterArcWhateverTheOrderOfTheEnds) {
  for (bool swap : {false, true}) {
    PortArc p;
    // 20° across the ±180° seam.
    widen_port(p, swap ? at(-170, 4.8, 2.0) : at(170, 4.8, 2.0),
               swap ? at(170, 4.8, 2.0) : at(-170, 4.8, 2.0));
    ASSERT_TRUE(p.open);
    EXPECT_NEAR(port_sweep_rad(p), 20 * kDeg, 1e-12);
    EXPECT_NEAR(angle_deg(p.start), 170.0, 1e-9);
    EXPECT_NEAR(p.radius_mm, 4.8, 1e-12);
    EXPECT_NEAR(p.z_mm, 2.0, 1e-12);
    const PortSize size = port_size(p);
    EXPECT_NEAR(size.chord_mm, 2 * 4.8 * std::sin(10 * kDeg), 1e-12);
    EXPECT_NEAR(size.arc_mm, 4.8 * 20 * kDeg, 1e-12);
    EXPECT_NEAR(port_middle(p).x(), -4.8, 1e-12);
  }
}

TEST(PortArc, WideningKeepsTheSmallestArcHoldingOldAndNew) {
  PortArc p;
  widen_port(p, at(10), at(30));
  widen_port(p, at(25), at(45));  // overlaps on the ccw side
  EXPECT_NEAR(angle_deg(p.start), 10.0, 1e-9);
  EXPECT_NEAR(angle_deg(p.end), 45.0, 1e-9);
  widen_port(p, at(0), at(5));  // disjoint, just cw of the start
  EXPECT_NEAR(angle_deg(p.start), 0.0, 1e-9);
  EXPECT_NEAR(angle_deg(p.end), 45.0, 1e-9);
  widen_port(p, at(15), at(20));  // inside: nothing moves
  EXPECT_NEAR(angle_deg(p.start), 0.0, 1e-9);
  EXPECT_NEAR(angle_deg(p.end), 45.0, 1e-9);
  widen_port(p, at(-100), at(-90));  // far cw: the short way round is through 0°
  EXPECT_NEAR(angle_deg(p.start), -100.0, 1e-9);
  EXPECT_NEAR(angle_deg(p.end), 45.0, 1e-9);
  EXPECT_NEAR(port_sweep_rad(p), 145 * kDeg, 1e-12);
  EXPECT_NEAR(p.radius_mm, 5.0, 1e-12);
  widen_port(p, at(0, 4.0, 1.0), at(1, 6.0, 2.0));
  EXPECT_NEAR(p.radius_mm, 5.0, 1e-12) << "radius and height: the last ends' means";
  EXPECT_NEAR(p.z_mm, 1.5, 1e-12);
}

TEST(PortArc, PassesWithinSpanRadiusAndHeightOnly) {
  PortArc p;
  EXPECT_FALSE(port_passes(p, at(0))) << "closed port";
  widen_port(p, at(-10), at(10));
  const PortTolerance tol{0.2, 0.1, 0.0};
  EXPECT_TRUE(port_passes(p, at(0), tol));
  EXPECT_TRUE(port_passes(p, at(9.9), tol));
  EXPECT_TRUE(port_passes(p, at(-9.9), tol));
  EXPECT_FALSE(port_passes(p, at(10.5), tol));
  EXPECT_FALSE(port_passes(p, at(-10.5), tol));
  EXPECT_FALSE(port_passes(p, at(180), tol));
  EXPECT_TRUE(port_passes(p, at(0, 5.19, 2.59), tol));
  EXPECT_FALSE(port_passes(p, at(0, 5.21, 2.5), tol));
  EXPECT_FALSE(port_passes(p, at(0, 5.0, 2.61), tol));
  EXPECT_FALSE(port_passes(p, {0, 0, 2.5}, {10, 0.1, 0}));
  // 0.1 mm of lateral slack at r = 5 is 1.146°.
  EXPECT_TRUE(port_passes(p, at(11.1), {0.2, 0.1, 0.1}));
  EXPECT_FALSE(port_passes(p, at(11.2), {0.2, 0.1, 0.1}));
}

TEST(PortArc, NearestPointClampsToTheSpan) {
  PortArc p;
  widen_port(p, at(-10), at(10));
  EXPECT_NEAR((nearest_on_port(p, at(5, 7.0, 4.0)) - at(5)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((nearest_on_port(p, at(40, 2.0, 0.0)) - at(10)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((nearest_on_port(p, at(-60)) - at(-10)).norm(), 0.0, 1e-12);
  EXPECT_NEAR((nearest_on_port(p, at(-175)) - at(-10)).norm(), 0.0, 1e-12) << "nearer end";
  EXPECT_NEAR((nearest_on_port(p, at(175)) - at(10)).norm(), 0.0, 1e-12) << "nearer end";
  EXPECT_NEAR((nearest_on_port(p, {0, 0, 9}) - at(0)).norm(), 0.0, 1e-12) << "on the axis";
  // It is the nearest: no point of the arc is closer.
  const Vec3 q = at(33, 6.0, 1.0);
  const double best = (nearest_on_port(p, q) - q).norm();
  for (int k = -100; k <= 100; ++k) EXPECT_GE((at(0.1 * k) - q).norm(), best - 1e-12);
}

TEST(PortArc, BadInputThrowsNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  PortArc p;
  expect_invalid([&] { nearest_on_port(p, at(0)); }, "port");
  expect_invalid([&] { widen_port(p, {0, 0, 1}, at(0)); }, "end a");
  expect_invalid([&] { widen_port(p, at(0), {nan, 0, 0}); }, "end b");
  EXPECT_FALSE(p.open) << "a throwing widen leaves the port closed";
  widen_port(p, at(0), at(1));
  expect_invalid([&] { port_passes(p, {nan, 0, 0}); }, "point");
  expect_invalid([&] { port_passes(p, at(0), {-1, 0, 0}); }, "tolerance");
  expect_invalid([&] { port_passes(p, at(0), {nan, 0, 0}); }, "tolerance");
  expect_invalid([&] { nearest_on_port(p, {0, nan, 0}); }, "point");
}

}  // namespace
}  // namespace phaco::incision
