// A scene built from a drill file (issue 7 item 1; data/drills, docs/drills.md): the difficulty
// reaches the eye parameters (the scenario's own overrides still win), the hands may hold only the
// drill's tools, a drill file of another drill or an unknown level is refused naming the field.
#include <gtest/gtest.h>

#include <string>

#include "components/tets.hpp"
#include "engine/core/error.hpp"
#include "procedures/eye/difficulty.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "tests/support/expect_invalid.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

Scenario scenario(Drill drill, ToolKind right_tool) {
  Scenario s;
  s.source = "test.json";
  s.drill = drill;
  s.eye.level = 1;
  s.duration_s = 0.1;
  s.hands.push_back({Hand::Right, right_tool, {TrackSample{0.0, Vec3(0, 0, 3.5)}}});
  return s;
}

std::unique_ptr<Scene> build(const Scenario& s) {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  return build_scene(s, o);
}

std::string error_of(const Scenario& s) {
  return test::input_error_of([&] { build(s); });
}

TEST(DrillScene, TheHardLevelReachesTheEye) {
  Scenario s = scenario(Drill::Capsulorhexis, ToolKind::Cystotome);
  s.difficulty = "hard";
  const auto scene = build(s);
  EXPECT_EQ(scene->drill.drill, Drill::Capsulorhexis);
  EXPECT_FALSE(scene->drill.title.empty());
  ASSERT_TRUE(scene->difficulty.patient_age_years);
  const eye::EyeParams standard = eye::default_eye_params();
  EXPECT_DOUBLE_EQ(scene->params.get("capsule.youngs_modulus_kpa"),
                   eye::capsule_modulus_for_age_kpa(*scene->difficulty.patient_age_years));
  EXPECT_GT(scene->params.get("capsule_model.prestretch"), standard.get("capsule_model.prestretch"))
      << "anterior bowing";
  EXPECT_LT(scene->params.get("cornea.posterior_apex_z_mm"),
            standard.get("cornea.posterior_apex_z_mm"))
      << "shallow chamber";
  // The scenario's explicit override is applied last and wins.
  s.eye.overrides["capsule.youngs_modulus_kpa"] = 2500;
  EXPECT_DOUBLE_EQ(build(s)->params.get("capsule.youngs_modulus_kpa"), 2500);
}

TEST(DrillScene, TheDefaultLevelIsTheEyeFileAsIs) {
  const auto scene = build(scenario(Drill::Capsulorhexis, ToolKind::Cystotome));
  EXPECT_EQ(scene->params.values, eye::default_eye_params().values);
}

TEST(DrillScene, AHarderNucleusTakesLessUltrasound) {
  Scenario s = scenario(Drill::PhacoSculpting, ToolKind::PhacoProbe);
  const auto standard = build(s);
  s.difficulty = "hard";
  const auto hard = build(s);
  const auto power = [](Scene& scene) {
    return scene.world.at<LensSculpting>(*scene.body(BodyPart::Lens)).ultrasound_power;
  };
  EXPECT_NEAR(power(*hard),
              power(*standard) * 0.5 / hard->params.get("lens_model.nucleus_hardness"), 1e-12);
  EXPECT_LT(power(*hard), power(*standard));
}

TEST(DrillScene, RefusesWhatTheDrillDoesNotAllow) {
  std::string e = error_of(scenario(Drill::Capsulorhexis, ToolKind::Keratome));
  EXPECT_NE(e.find("test.json: hands.right.tool: the capsulorhexis drill"), std::string::npos) << e;
  EXPECT_NE(e.find("gives the right hand cystotome, forceps; got keratome"), std::string::npos)
      << e;

  Scenario level = scenario(Drill::Capsulorhexis, ToolKind::Cystotome);
  level.difficulty = "nightmare";
  e = error_of(level);
  EXPECT_NE(e.find("test.json: difficulty: unknown level 'nightmare'"), std::string::npos) << e;

  Scenario other = scenario(Drill::Capsulorhexis, ToolKind::Cystotome);
  other.drill_file = eye::data_dir() / "drills" / "phaco_sculpting.json";
  e = error_of(other);
  EXPECT_NE(e.find("is a 'phaco_sculpting' drill; the scenario is 'capsulorhexis'"),
            std::string::npos)
      << e;
}

}  // namespace
}  // namespace phaco

namespace phaco {
namespace {

// The nucleus_removal drill (issue 19) runs the fragmenting lens only, gives the left hand the
// chopper, and starts from the grooved nucleus (cells removed before the first frame, the lens
// body's tets with them).
TEST(DrillScene, NucleusRemovalRefusesTheTetLensAndStartsGrooved) {
  Scenario s = scenario(Drill::NucleusRemoval, ToolKind::PhacoProbe);
  s.hands.insert(s.hands.begin(),
                 {Hand::Left, ToolKind::Chopper, {TrackSample{0.0, Vec3(-1, 0, 3.5)}}});
  const auto scene = build(s);
  const Entity lens = *scene->body(BodyPart::Lens);
  const LensFragments& lf = scene->world.at<LensFragments>(lens);
  EXPECT_TRUE(lf.nucleus_removal);
  EXPECT_GT(lf.grooved_volume_mm3, 10.0);
  EXPECT_EQ(scene->world.at<Tets>(lens).slots.live_count(), lf.lens.cells.alive_count);
  Scenario tets = s;
  tets.methods["lens.model"] = "tets";
  EXPECT_NE(error_of(tets).find("test.json: methods[\"lens.model\"]: the nucleus_removal drill"),
            std::string::npos)
      << error_of(tets);
  Scenario wrong = s;
  wrong.hands[0].tool = ToolKind::Hook;
  EXPECT_NE(error_of(wrong).find("hands.left.tool"), std::string::npos) << error_of(wrong);
}

}  // namespace
}  // namespace phaco
