#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "systems/incision/port_arc.hpp"
#include "systems/incision/wound.hpp"
#include "tests/systems/incision/incision_fixture.hpp"

namespace phaco::incision {
namespace {

using test::default_spheres;
using test::expect_invalid;

// Hours between two clock readings, the short way round (12 o'clock may read 12 or just above 0).
double clock_distance(double a, double b) {
  const double d = std::fmod(std::abs(a - b), 12.0);
  return std::min(d, 12.0 - d);
}

constexpr double kAdvanceMm = 4.0;  // tip travel along the axis; the shoulders pass both spheres
constexpr double kStepMm = 0.02;

// Advances the blade from the surface point by kAdvanceMm, then withdraws it to where it started
// outside; returns the tracker.
WoundTracker straight_pass(const CorneaSpheres& s, const KeratomeBlade& start) {
  const BladeFrame f = blade_frame(start);
  WoundTracker t;
  const int n = static_cast<int>(std::lround(kAdvanceMm / kStepMm));
  for (int i = -10; i <= n; ++i) {
    KeratomeBlade b = start;
    b.tip = start.tip + (i * kStepMm) * f.d;
    update_wound(t, b, s);
  }
  for (int i = n; i >= -10; --i) {
    KeratomeBlade b = start;
    b.tip = start.tip + (i * kStepMm) * f.d;
    update_wound(t, b, s);
  }
  return t;
}

// The measures of a straight pass against the geometry that was set: clock hour, entry angle,
// limbus distance, width W, and the tunnel and penetration from the line–sphere crossings along
// the axis (solved in the fixture, not by the code under test).
TEST(CornealWound, StraightPassMeasuresWhatWasSet) {
  const CorneaSpheres s = default_spheres();
  for (double hour : {9.0, 3.0, 10.5, 12.0}) {
    for (double angle : {10.0, 15.0, 25.0}) {
      const double limbus_distance = 0.3;
      const KeratomeBlade start = test::start_blade(s, hour, limbus_distance, angle);
      const BladeFrame f = blade_frame(start);
      const WoundTracker t = straight_pass(s, start);
      const CornealWound& w = t.wound;
      SCOPED_TRACE(testing::Message() << hour << " o'clock, " << angle << "°");
      ASSERT_TRUE(w.incised);
      ASSERT_TRUE(w.penetrated);
      EXPECT_NEAR(clock_distance(w.clock_hour, hour), 0.0, 0.01) << w.clock_hour;
      EXPECT_NEAR(w.entry_angle_deg, angle, 0.1);
      EXPECT_NEAR(w.limbus_distance_mm, limbus_distance, 1e-6);
      EXPECT_NEAR(w.width_mm, start.shape.width_mm, 1e-9);
      EXPECT_NEAR(w.inner_width_mm, start.shape.width_mm, 1e-9);
      const double t_in =
          test::line_sphere_far_root(start.tip, f.d, s.posterior_centre_z, s.posterior_radius_mm);
      EXPECT_NEAR(w.tunnel_length_mm, t_in, 1e-6);
      EXPECT_NEAR(w.penetration_depth_mm, kAdvanceMm - t_in, 1e-9);
      EXPECT_NEAR((w.outer.centre - start.tip).norm(), 0.0, 1e-6);
      EXPECT_NEAR((w.inner.centre - (start.tip + t_in * f.d)).norm(), 0.0, 1e-6);
      EXPECT_NEAR((w.outer.right - w.outer.left).norm(), w.width_mm, 1e-12);
      EXPECT_GT(t.cutting_frames, 0u);
      EXPECT_EQ(t.frames, 2u * (static_cast<uint32_t>(std::lround(kAdvanceMm / kStepMm)) + 11));
    }
  }
}

TEST(CornealWound, ShallowPassThatStopsInTheStromaHasNoTunnel) {
  const CorneaSpheres s = default_spheres();
  const KeratomeBlade start = test::start_blade(s, 9.0, 0.3, 15.0);
  WoundTracker t;
  for (int i = 0; i <= 20; ++i) {  // 0.4 mm: the tip stays in the stroma
    KeratomeBlade b = start;
    b.tip += 0.02 * i * blade_frame(start).d;
    update_wound(t, b, s);
  }
  EXPECT_TRUE(t.wound.incised);
  EXPECT_FALSE(t.wound.penetrated);
  EXPECT_EQ(t.wound.tunnel_length_mm, 0.0);
  EXPECT_EQ(t.wound.penetration_depth_mm, 0.0);
  EXPECT_GT(t.wound.width_mm, 0.0);
  EXPECT_LT(t.wound.width_mm, start.shape.width_mm) << "only the bevel went in";
}

TEST(CornealWound, BladeThatNeverTouchesLeavesNoWoundAndNoPort) {
  const CorneaSpheres s = default_spheres();
  KeratomeBlade b = test::start_blade(s, 9.0, 0.3, 15.0);
  b.tip -= 1.0 * blade_frame(b).d;
  WoundTracker t;
  for (int i = 0; i < 5; ++i) update_wound(t, b, s);
  EXPECT_FALSE(t.wound.incised);
  EXPECT_FALSE(t.punctured);
  EXPECT_FALSE(t.port.open);
  EXPECT_EQ(t.wound.width_mm, 0.0);
  EXPECT_EQ(t.cutting_frames, 0u);
  EXPECT_FALSE(port_passes(t.port, b.tip));
}

// The port after a straight 9 o'clock pass: it is the outer wound as an arc, so its span is the
// outer ends' (2·atan((W/2)/r_e), r_e their radial coordinate) and its chord is W; it holds the
// outer wound centre and a point 1 mm to the side (within the 1.2 mm half width), and not points
// 1 mm beyond either end of the wound.
TEST(CornealWound, PortArcHoldsTheWoundAndNotBesideIt) {
  const CorneaSpheres s = default_spheres();
  const KeratomeBlade start = test::start_blade(s, 9.0, 0.3, 15.0);
  const BladeFrame f = blade_frame(start);
  const WoundTracker t = straight_pass(s, start);
  ASSERT_TRUE(t.port.open);
  const double W = start.shape.width_mm;
  const Vec3 radial = Vec3(start.tip.x(), start.tip.y(), 0).normalized();
  const double r_e = t.wound.outer.left.dot(radial);
  EXPECT_NEAR(port_size(t.port).angle_rad, 2.0 * std::atan(0.5 * W / r_e), 1e-9);
  EXPECT_NEAR(port_size(t.port).chord_mm, W, 1e-9);
  EXPECT_NEAR(t.port.z_mm, t.wound.outer.left.z(), 1e-9);
  EXPECT_NEAR(clock_distance(clock_hour_of(port_middle(t.port)), 9.0), 0.0, 1e-9);

  const Vec3 centre = t.wound.outer.centre;
  const PortTolerance tol{0.3, 0.3, 0.0};
  EXPECT_TRUE(port_passes(t.port, centre, tol));
  EXPECT_TRUE(port_passes(t.port, centre + 1.0 * f.l, tol));
  EXPECT_TRUE(port_passes(t.port, centre - 1.0 * f.l, tol));
  // Beside the wound the radius grows too; a loose radial tolerance leaves the span to decide.
  const PortTolerance loose{1.0, 0.3, 0.0};
  const Vec3 beside = centre + (0.5 * W + 1.0) * f.l;
  EXPECT_FALSE(port_passes(t.port, beside, loose));
  EXPECT_FALSE(port_passes(t.port, centre - (0.5 * W + 1.0) * f.l, loose));
  EXPECT_TRUE(port_passes(t.port, beside, {1.0, 0.3, 1.5}))
      << "unless the lateral slack reaches it";
  EXPECT_FALSE(port_passes(t.port, centre + Vec3(0, 0, 1.0), tol)) << "1 mm above the wound";

  // A shaft point beside the port is pulled back to the nearer extremum.
  const Vec3 anchor = nearest_on_port(t.port, beside);
  EXPECT_NEAR(std::hypot(anchor.x(), anchor.y()), t.port.radius_mm, 1e-12);
  EXPECT_LT((anchor - beside).norm(),
            (nearest_on_port(t.port, centre - 2.2 * f.l) - beside).norm());
  EXPECT_TRUE(port_passes(t.port, anchor, {1e-9, 1e-9, 1e-9}));
  EXPECT_NEAR((anchor - t.wound.outer.right).norm(), 0.0, 1e-9) << "the right end of the wound";
}

// Sweeping the blade sideways while it is in (seed 001 §3.3 "enlargement and partial
// reorientation"): the port widens on the swept side only and its middle turns that way.
TEST(CornealWound, SidewaysSweepEnlargesAndReorientsThePort) {
  const CorneaSpheres s = default_spheres();
  const KeratomeBlade start = test::start_blade(s, 9.0, 0.3, 15.0);
  const BladeFrame f = blade_frame(start);
  WoundTracker t;
  KeratomeBlade b = start;
  for (int i = 0; i <= 150; ++i) {
    b.tip = start.tip + (0.02 * i) * f.d;
    update_wound(t, b, s);
  }
  const PortArc before = t.port;
  const double sweep_before = port_sweep_rad(before);
  const Vec3 middle_before = port_middle(before);
  for (int i = 1; i <= 25; ++i) {  // 0.5 mm to the blade's right
    KeratomeBlade m = b;
    m.tip = b.tip + (0.02 * i) * f.l;
    update_wound(t, m, s);
  }
  const double sweep_after = port_sweep_rad(t.port);
  EXPECT_GT(sweep_after, sweep_before + 0.05);
  // One extremum stays where it was (the blade's left end never moved further out).
  const bool start_kept = (t.port.start - before.start).norm() < 1e-12;
  const bool end_kept = (t.port.end - before.end).norm() < 1e-12;
  EXPECT_NE(start_kept, end_kept) << "exactly one extremum moved";
  // The middle turned toward the blade's right.
  EXPECT_GT((port_middle(t.port) - middle_before).dot(f.l), 0.0);
  // The widest section seen can only have grown.
  EXPECT_GE(t.wound.width_mm, start.shape.width_mm - 1e-9);
}

TEST(CornealWound, BadInputThrowsAndLeavesTheTrackerUnchanged) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const CorneaSpheres good = default_spheres();
  const KeratomeBlade blade = test::start_blade(good, 9.0, 0.3, 15.0);
  WoundTracker t;
  update_wound(t, blade, good);
  ASSERT_EQ(t.frames, 1u);

  CorneaSpheres s = good;
  s.anterior_radius_mm = 0;
  expect_invalid([&] { update_wound(t, blade, s); }, "anterior_radius_mm");
  s = good;
  s.posterior_centre_z = nan;
  expect_invalid([&] { update_wound(t, blade, s); }, "posterior_centre_z");
  s = good;
  s.limbus_radius_mm = -1;
  expect_invalid([&] { update_wound(t, blade, s); }, "limbus_radius_mm");
  KeratomeBlade b = blade;
  b.axis = b.lateral;
  expect_invalid([&] { update_wound(t, b, good); }, "lateral");
  b = blade;
  b.tip.y() = nan;
  expect_invalid([&] { update_wound(t, b, good); }, "tip");
  EXPECT_EQ(t.frames, 1u) << "a throwing update leaves the tracker as it was";
}

}  // namespace
}  // namespace phaco::incision
