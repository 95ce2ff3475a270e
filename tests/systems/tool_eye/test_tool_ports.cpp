// The scene's corneal ports (procedures/scene/tool_ports): the default ports sit in the cornea at
// the limbus with their tunnels pointing into the eye; the shipped drills measure by default
// (their files' "ports"); "tools.ports": "measure" on the first second of the capsulorhexis demo
// (scripted without ports: its shafts pass 0.2-0.4 mm off the port centres) turns the globe
// (finite, nonzero), reports the metrics with their targets and leaves the state hash alone;
// "off" has no ports; "constrain" moves the shown tool; the keratome, cutting its tunnel, is in no
// port; a bad mode is rejected naming the key.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "procedures/eye/eye_geometry.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/scene.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

TEST(ToolPorts, DefaultPortsSitInTheCorneaAtTheLimbus) {
  const eye::EyeParams params = eye::default_eye_params();
  const eye::EyeGeometry g = eye::eye_geometry(params);
  const auto ports = default_ports(params, 3.0, 11.0);
  ASSERT_EQ(ports.size(), 2u);
  for (const EyePort& p : ports) {
    const double rho = std::hypot(p.centre_mm.x(), p.centre_mm.y());
    EXPECT_LT(rho, g.limbus_radius);
    EXPECT_GT(rho, g.limbus_radius - 1.0);
    // Between the corneal spheres: inside the anterior one, outside the posterior one.
    EXPECT_LT((p.centre_mm - Vec3(0, 0, g.cornea_anterior_centre_z)).norm(),
              g.cornea_anterior_radius);
    EXPECT_GT((p.centre_mm - Vec3(0, 0, g.cornea_posterior_centre_z)).norm(),
              g.cornea_posterior_radius);
    EXPECT_NEAR(p.axis.norm(), 1.0, 1e-12);
    EXPECT_NEAR(p.width_dir.dot(p.axis), 0.0, 1e-12);
    EXPECT_LT(p.axis.dot(Vec3(p.centre_mm.x(), p.centre_mm.y(), 0.0)), 0.0);  // inward
    EXPECT_LT(p.axis.z(), 0.0);                                               // and down
  }
  EXPECT_NEAR(std::atan2(ports[0].centre_mm.y(), ports[0].centre_mm.x()), 0.0, 1e-12);  // 3:00
  EXPECT_NEAR(std::atan2(ports[1].centre_mm.y(), ports[1].centre_mm.x()), 2.0 * M_PI / 3.0,
              1e-12);  // 11:00
  EXPECT_DOUBLE_EQ(ports[0].width_mm, params.get("tools.keratome_width_mm"));
  EXPECT_DOUBLE_EQ(ports[1].width_mm, params.get("tool_eye.side_port_width_mm"));
}

Scenario incision_demo(const char* mode) {
  Scenario s = test::repo_scenario("corneal_incision_demo.json");
  if (mode) s.methods["tools.ports"] = mode;
  return s;
}

// Both hands in their ports from the first frame; one second keeps the test short.
Scenario rhexis_demo(const char* mode) {
  Scenario s = test::repo_scenario("capsulorhexis_demo.json");
  s.duration_s = 1.0;
  if (mode) s.methods["tools.ports"] = mode;
  return s;
}

TEST(ToolPorts, MeasureTurnsTheGlobeAndLeavesTheStateAlone) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole scenario runs; the Release pass runs them";
#endif
  const auto off = test::run_to_end(rhexis_demo("off"), 1);
  const auto by_drill = test::run_to_end(rhexis_demo(nullptr), 1);  // the drill file's "measure"
  const auto measured = test::run_to_end(rhexis_demo("measure"), 1);
  EXPECT_EQ(state_hash(*by_drill), state_hash(*off));
  EXPECT_EQ(state_hash(*measured), state_hash(*off));  // measure writes no ToolState
  EXPECT_EQ(ports_record(*off), nullptr);
  ASSERT_NE(ports_record(*by_drill), nullptr) << "the shipped drill measures by default";

  const PortsRecord* r = ports_record(*measured);
  ASSERT_NE(r, nullptr);
  EXPECT_GT(r->solves, 0u);
  EXPECT_TRUE(std::isfinite(r->max_rotation_deg));
  EXPECT_GT(r->max_rotation_deg, 1e-3);
  EXPECT_LT(r->max_rotation_deg, 30.0);
  EXPECT_GT(r->max_force_mn, 0.0);
  EXPECT_TRUE(std::isfinite(r->max_force_mn));
  EXPECT_DOUBLE_EQ(ports_record(*by_drill)->max_force_mn, r->max_force_mn);

  const DrillReport with = drill_report(*measured), without = drill_report(*off);
  ASSERT_TRUE(with.metrics.contains("globe.max_rotation_deg"));
  EXPECT_DOUBLE_EQ(with.metrics["globe.max_rotation_deg"].get<double>(), r->max_rotation_deg);
  EXPECT_DOUBLE_EQ(with.metrics["ports.max_force_mN"].get<double>(), r->max_force_mn);
  EXPECT_TRUE(with.targets["ports.max_force_mN"].contains("max"));
  EXPECT_TRUE(with.targets["globe.max_rotation_deg"].contains("max"));
  EXPECT_FALSE(without.metrics.contains("globe.max_rotation_deg"));
  EXPECT_FALSE(without.metrics.contains("ports.max_force_mN"));
  // Events only when the force crosses the threshold.
  bool stress = false;
  for (const auto& e : with.events) stress |= e["kind"] == "port_stress";
  EXPECT_EQ(stress, r->max_force_mn > r->stress_force_mn);
}

TEST(ToolPorts, ConstrainMovesTheShownToolFinitely) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole scenario runs; the Release pass runs them";
#endif
  const auto plain = test::run_to_end(rhexis_demo("off"), 1);
  const auto held = test::run_to_end(rhexis_demo("constrain"), 1);
  EXPECT_NE(state_hash(*held), state_hash(*plain));
  for (size_t i = 0; i < plain->tools.size(); ++i) {
    const ToolState& a = plain->world.at<ToolState>(plain->tools[i]);
    const ToolState& b = held->world.at<ToolState>(held->tools[i]);
    EXPECT_TRUE(b.pos.allFinite());
    EXPECT_TRUE(b.quat.coeffs().allFinite());
    EXPECT_LT((a.pos - b.pos).norm(), 1.0);  // the hand still leads
  }
}

// The keratome is cutting the main port (cornea_cutting): it is in no port, so the incision
// demo, whose keratome passes the main port 0.24 mm off its centre, turns no globe.
TEST(ToolPorts, TheKeratomeCuttingItsTunnelIsInNoPort) {
#if defined(__SANITIZE_ADDRESS__)
  GTEST_SKIP() << "whole scenario runs; the Release pass runs them";
#endif
  const auto measured = test::run_to_end(incision_demo("measure"), 1);
  const PortsRecord* r = ports_record(*measured);
  ASSERT_NE(r, nullptr);
  EXPECT_GT(r->solves, 0u);
  EXPECT_EQ(r->globe.tools[0].port, -1);
  EXPECT_EQ(r->max_force_mn, 0.0);
  EXPECT_EQ(r->max_rotation_deg, 0.0);
}

TEST(ToolPorts, RejectsAnUnknownMode) {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  try {
    build_scene(incision_demo("sometimes"), o);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    const std::string msg = e.what();
    EXPECT_NE(msg.find("tools.ports"), std::string::npos) << msg;
    EXPECT_NE(msg.find("sometimes"), std::string::npos) << msg;
  }
}

}  // namespace
}  // namespace phaco
