// A position-only input pivoting in its port (procedures/scene/port_pivot, issue 20 item 2): the
// pose function aims the shaft through the port's centre once the tip is in, blends before, and
// never jumps, for a bent tool its shaft's axis beside the tip; and in the sculpting scene under
// "constrain" the shown shaft passes through the main port's centre while the tip sweeps across the
// lens.
#include <gtest/gtest.h>

#include <cmath>

#include "components/tool.hpp"
#include "engine/io/tool_shape.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/scene/port_pivot.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

// Distance from `point` to the line through `tip` along `shaft`.
double off_line(const Vec3& tip, const Vec3& shaft, const Vec3& point) {
  const Vec3 d = point - tip;
  return (d - d.dot(shaft) * shaft).norm();
}

EyePort main_port() {
  return default_ports(eye::default_eye_params(), 3, 11)[0];
}

TEST(PortPivot, TheShaftRunsThroughThePortCentreOnceTheTipIsIn) {
  const EyePort port = main_port();
  ToolPose hand;
  hand.quat = Quat(Eigen::AngleAxisd(1.2, Vec3::UnitY()));  // some start orientation
  hand.grip = 0.5;
  // Tips across the anterior chamber, all well past the port.
  for (const Vec3& tip : {Vec3(1.5, -1.0, 1.5), Vec3(-1.0, 1.0, 1.2), Vec3(0.0, 0.0, 0.5)}) {
    hand.pos = tip;
    const ToolPose p = pivot_in_port(hand, port, ToolKind::PhacoProbe);
    const Vec3 shaft = p.quat * Vec3::UnitZ();
    EXPECT_LT(off_line(tip, shaft, port.centre_mm), 1e-9);
    EXPECT_GT(shaft.dot(port.centre_mm - tip), 0) << "tip → handle: the port is behind the tip";
    EXPECT_EQ(p.pos, tip);
    EXPECT_EQ(p.grip, 0.5);
    EXPECT_NEAR(p.quat.norm(), 1.0, 1e-12);
  }
  // Outside the eye (before the port's centre) the orientation is the hand's.
  hand.pos = port.centre_mm - 2.0 * port.axis;
  EXPECT_TRUE(
      pivot_in_port(hand, port, ToolKind::PhacoProbe).quat.isApprox(hand.quat.normalized(), 1e-12));
  // Going in along the axis the orientation turns continuously: no step above a small angle.
  Quat last = hand.quat;
  double worst = 0;
  for (int i = 0; i <= 400; ++i) {
    hand.pos = port.centre_mm + (-1.0 + 0.01 * i) * port.axis + Vec3(0, 0, -0.003 * i);
    const Quat q = pivot_in_port(hand, port, ToolKind::PhacoProbe).quat;
    worst = std::max(worst, q.angularDistance(last));
    last = q;
  }
  EXPECT_LT(worst, 0.05) << "rad per 0.01 mm step";
}

// A bent point (engine/io/tool_shape): it is the shaft's axis, beside the tip, that runs through
// the centre, the tip's line missing it by up to the bend; the pivot begins a bend deeper than a
// straight tool's and still never jumps.
TEST(PortPivot, ABentToolsShaftAxisRunsThroughThePortCentre) {
  const EyePort port = main_port();
  for (const ToolKind kind : {ToolKind::Cystotome, ToolKind::Chopper, ToolKind::Hook}) {
    const double bend = shaft_offset_local(kind).norm();
    ASSERT_GT(bend, 0.0);
    ToolPose hand;
    hand.quat = Quat(Eigen::AngleAxisd(1.2, Vec3::UnitY()));
    for (const Vec3& tip : {Vec3(1.5, -1.0, 1.5), Vec3(-1.0, 1.0, 1.2), Vec3(0.0, 0.0, 0.5)}) {
      hand.pos = tip;
      const ToolPose p = pivot_in_port(hand, port, kind);
      const ShaftAxis axis = shaft_axis(p, kind);
      EXPECT_LT(off_line(axis.point, axis.direction, port.centre_mm), 1e-9) << to_string(kind);
      EXPECT_GT(axis.direction.dot(port.centre_mm - tip), 0);
      // The old pivot, about the tip's line, puts the drawn shaft the bend's sine off the centre.
      const ToolPose straight = pivot_in_port(hand, port, ToolKind::PhacoProbe);
      const ShaftAxis old_axis = shaft_axis(straight, kind);
      EXPECT_GT(off_line(old_axis.point, old_axis.direction, port.centre_mm), 0.9 * bend);
    }
    // Just past the centre, nearer than the bend, the orientation is still the hand's.
    hand.pos = port.centre_mm + 0.9 * bend * port.axis;
    EXPECT_TRUE(pivot_in_port(hand, port, kind).quat.isApprox(hand.quat.normalized(), 1e-12));
    Quat last = hand.quat;
    double worst = 0;
    for (int i = 0; i <= 500; ++i) {
      hand.pos = port.centre_mm + (-1.0 + 0.01 * i) * port.axis + Vec3(0, 0, -0.003 * i);
      const Quat q = pivot_in_port(hand, port, kind).quat;
      worst = std::max(worst, q.angularDistance(last));
      last = q;
    }
    EXPECT_LT(worst, 0.05) << to_string(kind) << ": rad per 0.01 mm step";
  }
}

// The tip sweeps across the lens, the shaft given by the pose function (what the desktop input
// sends); under "constrain" the shown pose — the tool–eye equilibrium — keeps the shaft through
// the main port's centre (turned with the globe) within 0.05 mm.
TEST(PortPivot, UnderConstrainTheShownShaftPassesThroughThePortWhileTheTipMoves) {
  Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
  s.methods["tools.ports"] = "constrain";
  const EyePort port = main_port();
  const Quat start = Quat(0.719345, -0.075527, 0.690535, 0.0).normalized();
  s.duration_s = 1.0;
  for (HandTrack& h : s.hands) {
    if (h.hand != Hand::Right) continue;
    h.track.clear();
    const int n = static_cast<int>(std::llround(s.duration_s / s.dt_s));
    for (int f = 0; f <= n; ++f) {
      const double u = static_cast<double>(f) / n;
      TrackSample t;
      t.t = f * s.dt_s;
      t.pos = Vec3(2.0 - 3.5 * u, -1.2 + 2.4 * u, 1.8 - 0.4 * u);
      t.quat = pivot_in_port({t.pos, start, 0, 0}, port, ToolKind::PhacoProbe).quat;
      h.track.push_back(t);
    }
  }
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  auto scene = build_scene(s, o);
  Entity probe{};
  for (Entity e : scene->tools)
    if (scene->world.at<Tool>(e).hand == Hand::Right) probe = e;
  double worst = 0, travel = 0;
  Vec3 first = Vec3::Zero();
  for (uint64_t f = 0; f < s.frame_count(); ++f) {
    step(*scene);
    const ToolState& pose = scene->world.at<ToolState>(probe);
    const PortsRecord& r = *ports_record(*scene);
    const Vec3 c =
        r.eye.globe_centre_mm + r.globe.rotation * (port.centre_mm - r.eye.globe_centre_mm);
    worst = std::max(worst, off_line(pose.pos, pose.quat.normalized() * Vec3::UnitZ(), c));
    if (f == 0) first = pose.pos;
    travel = std::max(travel, (pose.pos - first).norm());
  }
  EXPECT_GT(travel, 3.0) << "the tip moved";
  EXPECT_LT(worst, 0.05) << "mm from the port centre";
}

}  // namespace
}  // namespace phaco
