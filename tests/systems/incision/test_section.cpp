#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "systems/incision/section.hpp"
#include "tests/systems/incision/incision_fixture.hpp"

namespace phaco::incision {
namespace {

using test::default_spheres;
using test::expect_invalid;

double off_sphere(const Vec3& p, double cz, double r) {
  return std::abs((p - Vec3(0, 0, cz)).norm() - r);
}

double off_outline(const KeratomeBlade& b, const Vec3& p) {
  const BladeFrame f = blade_frame(b);
  const Vec3 q = p - f.tip;
  return std::abs(outline_signed_distance(b.shape, q.dot(f.d), q.dot(f.l))) + std::abs(q.dot(f.n));
}

// A 9 o'clock approach on the default eye, advanced straight along its axis: nothing before the
// tip reaches the anterior sphere, a cut on the bevels that grows as it passes (checked against
// the bevel/circle quadratic solved here), then the full width W on the sides.
TEST(BladeSection, GrowsAlongTheBevelThenHoldsTheBladeWidth) {
  const CorneaSpheres s = default_spheres();
  const KeratomeBlade start = test::start_blade(s, 9.0, 0.3, 15.0);
  const BladeFrame f0 = blade_frame(start);
  const double W = start.shape.width_mm, sh = start.shape.shoulder_mm;
  const double cz = s.anterior_centre_z, R = s.anterior_radius_mm;
  const double k = 0.5 * W / sh;  // bevel: |v| = k·(−u)

  double last_width = 0.0;
  int before = 0, bevel = 0, sides = 0;
  for (int i = -50; i <= 400; ++i) {
    const double a = 0.01 * i;  // advance of the tip past the surface point, mm
    KeratomeBlade b = start;
    b.tip = start.tip + a * f0.d;
    const BladeSection x = blade_section(b, cz, R);
    ASSERT_TRUE(x.left.allFinite() && x.right.allFinite() && x.middle.allFinite());
    if (a < 0.0) {
      EXPECT_FALSE(x.touches) << "a = " << a;
      EXPECT_FALSE(x.has_puncture) << "a = " << a;
      ++before;
      continue;
    }
    ASSERT_TRUE(x.touches) << "a = " << a;
    ASSERT_TRUE(x.has_puncture);
    EXPECT_NEAR((x.puncture - start.tip).norm(), 0.0, 1e-9) << "puncture = the surface point";
    EXPECT_LT(off_sphere(x.left, cz, R), 1e-9);
    EXPECT_LT(off_sphere(x.right, cz, R), 1e-9);
    EXPECT_LT(off_sphere(x.middle, cz, R), 1e-9);
    EXPECT_LT(off_outline(b, x.left), 1e-9);
    EXPECT_LT(off_outline(b, x.right), 1e-9);
    EXPECT_NEAR(x.left_v, -x.right_v, 1e-9) << "symmetric approach";
    EXPECT_GE(x.width_mm, last_width - 1e-12) << "the section never shrinks while advancing";
    last_width = x.width_mm;
    // The middle of the cut is on the axis line: the puncture point.
    EXPECT_NEAR((x.middle - start.tip).norm(), 0.0, 1e-9) << "a = " << a;

    // The plane circle, from first principles: centre (u_c, v_c) in blade coordinates, radius ρ.
    const BladeFrame f = blade_frame(b);
    const Vec3 w = Vec3(0, 0, cz) - f.tip;
    const double uc = w.dot(f.d), vc = w.dot(f.l), h = w.dot(f.n);
    const double rho = std::sqrt(R * R - h * h);
    EXPECT_NEAR(vc, 0.0, 1e-12);
    EXPECT_NEAR(x.circle_radius_mm, rho, 1e-9);
    if (x.right_edge == OutlineEdge::RightBevel) {
      EXPECT_EQ(x.left_edge, OutlineEdge::LeftBevel);
      // (1 + k²)u² − 2u_c·u + u_c² − ρ² = 0 with u in [−s, 0].
      const double A = 1 + k * k, disc = uc * uc - A * (uc * uc - rho * rho);
      ASSERT_GE(disc, 0.0);
      int roots = 0;
      for (double u : {(uc - std::sqrt(disc)) / A, (uc + std::sqrt(disc)) / A}) {
        if (u < -sh - 1e-12 || u > 1e-12) continue;
        ++roots;
        EXPECT_NEAR(x.width_mm, 2.0 * k * -u, 1e-9) << "a = " << a;
      }
      EXPECT_EQ(roots, 1);
      EXPECT_LE(x.width_mm, W + 1e-12);
      ++bevel;
    } else {
      EXPECT_EQ(x.right_edge, OutlineEdge::RightSide);
      EXPECT_EQ(x.left_edge, OutlineEdge::LeftSide);
      EXPECT_NEAR(x.left_v, -0.5 * W, 1e-12);
      EXPECT_NEAR(x.right_v, 0.5 * W, 1e-12);
      EXPECT_NEAR(x.width_mm, W, 1e-9) << "chord between the sides";
      // The cut arc exceeds the chord by 2ρ·(asin q − q), q = W/2ρ: between the series' first
      // term W³/(24ρ²) and that times 1 + 0.45q²/(1 − q²) (later coefficients are below 0.45).
      const double arc = 2.0 * rho * std::asin(0.5 * W / rho);
      EXPECT_NEAR(x.arc_mm, arc, 1e-9);
      const double lead = W * W * W / (24 * rho * rho), q2 = 0.25 * W * W / (rho * rho);
      EXPECT_GT(x.arc_mm - W, lead - 1e-12);
      EXPECT_LT(x.arc_mm - W, lead * (1 + 0.45 * q2 / (1 - q2)) + 1e-12);
      ++sides;
    }
  }
  EXPECT_EQ(before, 50);
  EXPECT_GT(bevel, 20) << "the bevel passes over several steps";
  EXPECT_GT(sides, 20) << "the shoulders get through";
}

// Yawed 10° about the blade normal: the ends are still on the sides (v = ∓W/2) but at different
// depths along the axis, so the chord is √(W² + Δu²) > W.
TEST(BladeSection, YawedBladeCutsOnBothSidesWithALongerChord) {
  const CorneaSpheres s = default_spheres();
  KeratomeBlade b = test::start_blade(s, 9.0, 0.3, 15.0);
  const BladeFrame f = blade_frame(b);
  const Eigen::AngleAxisd yaw(10.0 * std::numbers::pi / 180.0, f.n);
  b.axis = yaw * f.d;
  b.lateral = yaw * f.l;
  b.tip += 3.0 * b.axis;
  const BladeSection x = blade_section(b, s.anterior_centre_z, s.anterior_radius_mm);
  ASSERT_TRUE(x.touches);
  EXPECT_EQ(x.left_edge, OutlineEdge::LeftSide);
  EXPECT_EQ(x.right_edge, OutlineEdge::RightSide);
  const double W = b.shape.width_mm;
  EXPECT_NEAR(x.left_v, -0.5 * W, 1e-12);
  EXPECT_NEAR(x.right_v, 0.5 * W, 1e-12);
  const double du = (x.right - x.left).dot(b.axis.normalized());
  EXPECT_GT(std::abs(du), 0.05);
  EXPECT_NEAR(x.width_mm, std::hypot(W, du), 1e-9);
}

TEST(BladeSection, TipExactlyOnTheSurfaceIsAZeroWidthCutAtTheTip) {
  KeratomeBlade b;
  b.tip = {0, 0, 5};
  b.axis = {0, 0, -1};  // straight in along the radius: the blade behind the tip is outside
  b.lateral = {0, 1, 0};
  const BladeSection x = blade_section(b, 0.0, 5.0);
  ASSERT_TRUE(x.touches);
  EXPECT_TRUE(x.tip_inside);
  ASSERT_TRUE(x.has_puncture);
  EXPECT_NEAR((x.left - b.tip).norm(), 0.0, 1e-12);
  EXPECT_NEAR((x.right - b.tip).norm(), 0.0, 1e-12);
  EXPECT_NEAR((x.puncture - b.tip).norm(), 0.0, 1e-12);
  EXPECT_NEAR(x.width_mm, 0.0, 1e-12);
  EXPECT_EQ(x.arc_mm, 0.0);
}

TEST(BladeSection, PlaneTangentToTheSphereTouchesAtOnePoint) {
  KeratomeBlade b;
  b.tip = {0.5, 0, 5};  // blade plane z = 5 touches the sphere |p| = 5 at (0, 0, 5), on the blade
  b.axis = {1, 0, 0};
  b.lateral = {0, -1, 0};
  BladeSection x = blade_section(b, 0.0, 5.0);
  ASSERT_TRUE(x.touches);
  EXPECT_TRUE(x.closed);
  EXPECT_FALSE(x.tip_inside);
  EXPECT_NEAR((x.left - Vec3(0, 0, 5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR((x.right - Vec3(0, 0, 5)).norm(), 0.0, 1e-9);
  EXPECT_NEAR(x.width_mm, 0.0, 1e-9);

  b.tip.z() = 5.001;  // just above: no contact
  x = blade_section(b, 0.0, 5.0);
  EXPECT_FALSE(x.touches);
  EXPECT_EQ(x.width_mm, 0.0);
}

TEST(BladeSection, SphereGrazingASideEdgeGivesOneFiniteEnd) {
  // Blade in the plane y = 0, lateral +z: the right side runs along z = −3, y = 0, x in [−4, 0.5],
  // tangent to the sphere |p| = 3 at (0, 0, −3).
  KeratomeBlade b;
  b.tip = {2, 0, -4.2};
  b.axis = {1, 0, 0};
  b.lateral = {0, 0, 1};
  const BladeSection x = blade_section(b, 0.0, 3.0);
  ASSERT_TRUE(x.touches);
  EXPECT_EQ(x.right_edge, OutlineEdge::RightSide);
  EXPECT_NEAR((x.left - Vec3(0, 0, -3)).norm(), 0.0, 1e-6);
  EXPECT_NEAR((x.right - Vec3(0, 0, -3)).norm(), 0.0, 1e-6);
  EXPECT_LT(x.width_mm, 1e-6);
  EXPECT_TRUE(x.middle.allFinite());
}

TEST(BladeSection, SmallSphereInsideTheBladeIsAClosedCut) {
  KeratomeBlade b;
  b.tip = {3, 0, 0};  // plane z = 0, blade over x in [−3, 3], |y| <= 1.2 behind the shoulders
  b.axis = {1, 0, 0};
  b.lateral = {0, -1, 0};
  const BladeSection x = blade_section(b, 0.1, 0.3);
  ASSERT_TRUE(x.touches);
  EXPECT_TRUE(x.closed);
  const double rho = std::sqrt(0.09 - 0.01);
  EXPECT_NEAR(x.width_mm, 2 * rho, 1e-12);
  EXPECT_NEAR(x.arc_mm, 2 * std::numbers::pi * rho, 1e-12);
}

TEST(BladeSection, FarAwayOrBuriedBladeHasNoCut) {
  KeratomeBlade b;
  b.tip = {20, 0, 20};
  BladeSection x = blade_section(b, 0.0, 5.0);
  EXPECT_FALSE(x.touches);
  EXPECT_FALSE(x.tip_inside);
  EXPECT_FALSE(x.has_puncture);

  b.tip = {1, 0, 0};  // the whole blade inside a sphere of radius 50: no surface crossed
  x = blade_section(b, 0.0, 50.0);
  EXPECT_FALSE(x.touches);
  EXPECT_TRUE(x.tip_inside);
  ASSERT_TRUE(x.has_puncture) << "the axis line behind the tip still crosses the sphere";
  EXPECT_NEAR(x.puncture.norm(), 50.0, 1e-9);
  EXPECT_LT(x.puncture.x(), 0.0) << "behind the tip";
}

TEST(BladeSection, BadInputThrowsNamingTheField) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  KeratomeBlade b;
  expect_invalid([&] { blade_section(b, nan, 5.0); }, "sphere_centre_z");
  expect_invalid([&] { blade_section(b, 0.0, 0.0); }, "sphere_radius_mm");
  expect_invalid([&] { blade_section(b, 0.0, -1.0); }, "sphere_radius_mm");
  expect_invalid([&] { blade_section(b, 0.0, nan); }, "sphere_radius_mm");
  KeratomeBlade t = b;
  t.tip.z() = nan;
  expect_invalid([&] { blade_section(t, 0.0, 5.0); }, "tip");
  KeratomeBlade z = b;
  z.axis = Vec3::Zero();
  expect_invalid([&] { blade_section(z, 0.0, 5.0); }, "axis");
  KeratomeBlade p = b;
  p.lateral = p.axis;
  expect_invalid([&] { blade_section(p, 0.0, 5.0); }, "lateral");
}

}  // namespace
}  // namespace phaco::incision
