// Issue 4's capsulorhexis figures: a scripted ideal rhexis (puncture, flap, a circular pull of
// radius 2.6 mm with regrasps every 90°) gives a closed, round opening of diameter 5.2 ± 0.3 mm;
// an outward pull raises the run-out warning before the tear crosses 3.5 mm from the axis.
#include <gtest/gtest.h>

#include <string>
#include <tuple>
#include <vector>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "procedures/rhexis/cut_fidelity.hpp"
#include "procedures/rhexis/scripted_rhexis.hpp"
#include "tests/systems/cut/cut_sheet.hpp"

namespace phaco::rhexis {
namespace {

cut::CutSettings cut_settings() {
  cut::CutSettings s;
  s.snap.vertex_snap_mm = 0.01;
  s.snap.edge_snap_mm = 0.005;
  return s;
}

class IdealRhexis
    : public ::testing::TestWithParam<std::tuple<int, eye::CapsuleLayout, tear::TearRule>> {};

TEST_P(IdealRhexis, ClosesARoundOpeningOfTheTargetDiameter) {
  const auto [level, layout, rule] = GetParam();
  cut::test::CutSheet sheet = cut::test::cut_sheet(
      eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(level), layout));
  // The capsule's rim is held (anchored) as in the scene.
  for (uint32_t v = 0; v < sheet.particles.slots.size(); ++v)
    if (std::hypot(sheet.particles.x[v], sheet.particles.y[v]) > 0.999 * 4.5)
      sheet.particles.kind[v] = ParticleKind::Anchored;
  cut::CutMesh m = sheet.mesh();
  tear::TearSettings tear;
  tear.rule = rule;
  const RhexisResult r = run_scripted_rhexis(m, RhexisScript{}, tear, cut_settings());
  RecordProperty("diameter_mm", std::to_string(r.opening.diameter_mm));
  RecordProperty("circularity", std::to_string(r.opening.circularity));
  RecordProperty("tear_steps", std::to_string(r.tear_steps));
  EXPECT_TRUE(r.tear_complete);
  ASSERT_TRUE(r.opening.complete) << "the disc came free";
  EXPECT_GE(r.opening.circularity, 0.9);
  EXPECT_NEAR(r.opening.diameter_mm, 5.2, 0.3);
  EXPECT_NEAR(r.opening.ellipse_diameter_mm, 5.2, 0.3);
  EXPECT_LT(r.opening.centering_mm, 0.4);
  EXPECT_EQ(r.radial_tearouts, 0u);
  EXPECT_GE(r.regrasps, 3u);
  EXPECT_TRUE(cut::test::sound(sheet));
}

INSTANTIATE_TEST_SUITE_P(Capsule, IdealRhexis,
                         ::testing::Values(std::make_tuple(3, eye::CapsuleLayout::Curvilinear,
                                                           tear::TearRule::FlapForce),
                                           std::make_tuple(3, eye::CapsuleLayout::Isotropic,
                                                           tear::TearRule::FlapForce)));

TEST(OutwardPull, WarnsBeforeTheTearLeavesTheSafeZoneAndRecordsTheTearOut) {
  cut::test::CutSheet sheet = cut::test::cut_sheet(eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(3), eye::CapsuleLayout::Curvilinear));
  cut::CutMesh m = sheet.mesh();
  RhexisScript script;
  script.pull = RhexisScript::Pull::Outward;
  tear::TearSettings tear;
  const RhexisResult r = run_scripted_rhexis(m, script, tear, cut_settings());
  RecordProperty("first_warning_radius_mm", std::to_string(r.first_warning_radius_mm));
  ASSERT_GE(r.runout_warnings, 1u);
  EXPECT_GT(r.first_warning_radius_mm, 0.0);
  EXPECT_LT(r.first_warning_radius_mm, tear.safe_radius_mm)
      << "the warning comes before the tear leaves the zone";
  EXPECT_EQ(r.radial_tearouts, 1u) << "the runaway radial tear is recorded, once";
  EXPECT_GT(r.tearout_radius_mm, tear.safe_radius_mm);
  EXPECT_FALSE(r.opening.complete);
  EXPECT_TRUE(cut::test::sound(sheet));
}

// A straight 4 mm stroke across the capsule: the cut follows the tool to its end, within the
// snapping distance (both ways of the Hausdorff distance), on every level and layout tested.
class StraightCut : public ::testing::TestWithParam<std::tuple<int, eye::CapsuleLayout>> {};

TEST_P(StraightCut, FollowsTheToolWithinTheSnapDistance) {
  const auto [level, layout] = GetParam();
  cut::test::CutSheet sheet = cut::test::cut_sheet(
      eye::make_capsule(eye::default_eye_params(), eye::resolution_for_level(level), layout));
  for (uint32_t v = 0; v < sheet.particles.slots.size(); ++v)
    if (std::hypot(sheet.particles.x[v], sheet.particles.y[v]) > 0.999 * 4.5)
      sheet.particles.kind[v] = ParticleKind::Anchored;
  cut::CutMesh m = sheet.mesh();
  const cut::CutSettings settings = cut_settings();
  cut::CutPath path;
  cut::EditLog log;
  uint32_t hint = 0;
  std::vector<Vec3> tool;
  for (int k = 0; k <= 40; ++k) {
    tool.push_back(surface_below(m, -2.0 + 0.1 * k, -0.3 + 0.0175 * k, hint, settings.snap));
    cut::cut_towards(m, path, tool.back(), settings, log);
  }
  const CutFidelity f = measure_cut_fidelity(m, tool);
  RecordProperty("hausdorff_mm", std::to_string(f.hausdorff_mm));
  EXPECT_GT(f.lip_edges, 20u);
  EXPECT_LE(f.cut_to_tool_mm, path.max_snap_mm + 1e-3);
  // The far way round samples the lips at ends and midpoints: half the longest lip of slack.
  EXPECT_LE(f.tool_to_cut_mm, path.max_snap_mm + 0.2);
  EXPECT_LT((cut::particle_position(sheet.particles, path.tip) - tool.back()).norm(), 0.1)
      << "the cut reached the end";
  EXPECT_TRUE(cut::test::sound(sheet));
}

INSTANTIATE_TEST_SUITE_P(Capsule, StraightCut,
                         ::testing::Combine(::testing::Values(0, 1, 2, 3),
                                            ::testing::Values(eye::CapsuleLayout::Curvilinear,
                                                              eye::CapsuleLayout::Isotropic)));

TEST(ScriptedRhexis, RefusesABadScript) {
  cut::test::CutSheet sheet = cut::test::cut_sheet(eye::make_capsule(
      eye::default_eye_params(), eye::resolution_for_level(0), eye::CapsuleLayout::Curvilinear));
  cut::CutMesh m = sheet.mesh();
  RhexisScript script;
  script.radius_mm = -1.0;
  EXPECT_THROW(run_scripted_rhexis(m, script, {}, cut_settings()), std::invalid_argument);
}

}  // namespace
}  // namespace phaco::rhexis
