#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "systems/incision/keratome.hpp"
#include "tests/systems/incision/incision_fixture.hpp"

namespace phaco::incision {
namespace {

using test::default_spheres;
using test::expect_invalid;

constexpr double kDeg = std::numbers::pi / 180.0;

TEST(Keratome, StartBladeSitsOnTheAnteriorSphereAtTheRequestedPlace) {
  const CorneaSpheres s = default_spheres();
  for (double hour : {9.0, 3.0, 12.0, 10.5, 0.25, 6.0}) {
    for (double angle : {10.0, 15.0, 25.0}) {
      const KeratomeBlade b = test::start_blade(s, hour, 0.3, angle);
      const Vec3 c(0, 0, s.anterior_centre_z);
      EXPECT_NEAR((b.tip - c).norm(), s.anterior_radius_mm, 1e-12) << hour;
      EXPECT_NEAR(std::hypot(b.tip.x(), b.tip.y()), s.limbus_radius_mm - 0.3, 1e-12);
      EXPECT_NEAR(clock_hour_of(b.tip), hour == 0.0 ? 12.0 : hour, 1e-12);
      const BladeFrame f = blade_frame(b);
      EXPECT_NEAR(std::asin(-f.d.z()) / kDeg, angle, 1e-12);
      // Toward the axis: the horizontal part of d is antiparallel to the tip's radial direction.
      const Vec3 radial = Vec3(b.tip.x(), b.tip.y(), 0).normalized();
      EXPECT_NEAR(Vec3(f.d.x(), f.d.y(), 0).normalized().dot(radial), -1.0, 1e-12);
      // Lateral along the limbus, horizontal, to the blade's right seen from +z.
      EXPECT_NEAR(f.l.z(), 0.0, 1e-15);
      EXPECT_NEAR(f.l.dot(radial), 0.0, 1e-12);
      EXPECT_LT(Vec3(f.d.x(), f.d.y(), 0).cross(f.l).z(), 0.0) << "l = d_h × ẑ is to the right";
      EXPECT_GT(f.n.z(), 0.0) << "normal = l × d is the upper face";
    }
  }
}

TEST(Keratome, ClockHourOfTheFourCardinalDirections) {
  EXPECT_NEAR(clock_hour_of({0, 1, 0}), 12.0, 1e-12);
  EXPECT_NEAR(clock_hour_of({1, 0, 0}), 3.0, 1e-12);
  EXPECT_NEAR(clock_hour_of({0, -1, 0}), 6.0, 1e-12);
  EXPECT_NEAR(clock_hour_of({-1, 0, 0}), 9.0, 1e-12);
  EXPECT_NEAR(clock_hour_of({-1, 1, 5}), 10.5, 1e-12);
  EXPECT_EQ(clock_hour_of({0, 0, 3}), 12.0);
}

TEST(Keratome, OutlineIsThePentagonOfWidthShoulderAndLength) {
  KeratomeBlade b;
  b.tip = {1, 2, 3};
  b.axis = {2, 0, 0};        // normalised by blade_frame
  b.lateral = {0.5, -1, 0};  // its part along the axis is removed
  const BladeFrame f = blade_frame(b);
  EXPECT_NEAR((f.d - Vec3::UnitX()).norm(), 0.0, 1e-15);
  EXPECT_NEAR((f.l + Vec3::UnitY()).norm(), 0.0, 1e-15);
  const BladeOutline o = blade_outline(f, b.shape);
  const double s = b.shape.shoulder_mm, L = b.shape.length_mm, h = 0.5 * b.shape.width_mm;
  EXPECT_NEAR((o.corner[0] - b.tip).norm(), 0.0, 1e-15);
  EXPECT_NEAR((o.corner[1] - (b.tip + Vec3(-s, -h, 0))).norm(), 0.0, 1e-15);
  EXPECT_NEAR((o.corner[2] - (b.tip + Vec3(-L, -h, 0))).norm(), 0.0, 1e-15);
  EXPECT_NEAR((o.corner[3] - (b.tip + Vec3(-L, h, 0))).norm(), 0.0, 1e-15);
  EXPECT_NEAR((o.corner[4] - (b.tip + Vec3(-s, h, 0))).norm(), 0.0, 1e-15);
}

TEST(Keratome, ToolPoseRoundTripAndTheDemoScenarioPose) {
  const CorneaSpheres s = default_spheres();
  const KeratomeBlade b = test::start_blade(s, 10.5, 0.4, 20.0);
  ToolPose pose;
  pose.pos = b.tip;
  pose.quat = tool_quat_for_blade(b.axis, b.lateral);
  EXPECT_NEAR(pose.quat.norm(), 1.0, 1e-12);
  const BladeFrame a = blade_frame(b), r = blade_frame(blade_from_tool_pose(pose));
  EXPECT_NEAR((a.d - r.d).norm(), 0.0, 1e-12);
  EXPECT_NEAR((a.l - r.l).norm(), 0.0, 1e-12);

  // data/scenarios/corneal_incision_demo.json: quat (0.777146, 0, 0.62932, 0), the track moving
  // by (-0.7, 0, -0.1488) per step: the blade advances toward -x, 12° below the iris plane.
  ToolPose demo;
  demo.quat = Quat(0.777146, 0, 0.62932, 0);
  const BladeFrame d = blade_frame(blade_from_tool_pose(demo));
  EXPECT_NEAR(d.d.dot(Vec3(-0.7, 0, -0.1488).normalized()), 1.0, 1e-6);
  EXPECT_NEAR(std::asin(-d.d.z()) / kDeg, 12.0, 0.01);
  EXPECT_NEAR((d.l - Vec3::UnitY()).norm(), 0.0, 1e-6);
}

TEST(Keratome, BadInputThrowsNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const double inf = std::numeric_limits<double>::infinity();
  KeratomeBlade good;
  auto with = [&](auto edit) {
    KeratomeBlade b = good;
    edit(b);
    return b;
  };
  expect_invalid([&] { blade_frame(with([&](auto& b) { b.tip.x() = nan; })); }, "tip");
  expect_invalid([&] { blade_frame(with([&](auto& b) { b.axis.y() = inf; })); }, "axis");
  expect_invalid([&] { blade_frame(with([](auto& b) { b.axis.setZero(); })); }, "axis");
  expect_invalid([&] { blade_frame(with([](auto& b) { b.lateral = -3.0 * b.axis; })); }, "lateral");
  expect_invalid([&] { blade_frame(with([](auto& b) { b.lateral.setZero(); })); }, "lateral");
  expect_invalid([&] { blade_frame(with([](auto& b) { b.shape.width_mm = 0; })); }, "width_mm");
  expect_invalid([&] { blade_frame(with([&](auto& b) { b.shape.thickness_mm = nan; })); },
                 "thickness_mm");
  expect_invalid([&] { blade_frame(with([](auto& b) { b.shape.shoulder_mm = -0.1; })); },
                 "shoulder_mm");
  expect_invalid([&] { blade_frame(with([](auto& b) { b.shape.length_mm = 1.0; })); }, "length_mm");
  EXPECT_NO_THROW(blade_frame(with([](auto& b) { b.shape.shoulder_mm = 0; })));

  const CorneaSpheres s = default_spheres();
  expect_invalid([&] { test::start_blade(s, 9, 0.3, 0.0); }, "entry_angle_deg");
  expect_invalid([&] { test::start_blade(s, 9, 0.3, 90.0); }, "entry_angle_deg");
  expect_invalid([&] { test::start_blade(s, nan, 0.3, 15.0); }, "clock_hour");
  expect_invalid([&] { test::start_blade(s, 9, 6.0, 15.0); }, "limbus_distance_mm");
  expect_invalid([&] { test::start_blade(s, 9, -3.0, 15.0); }, "limbus_distance_mm");
  expect_invalid([&] { tool_quat_for_blade(Vec3::Zero(), Vec3::UnitY()); }, "axis");
  ToolPose bad;
  bad.quat = Quat(0, 0, 0, 0);
  expect_invalid([&] { blade_from_tool_pose(bad); }, "quat");
}

}  // namespace
}  // namespace phaco::incision
