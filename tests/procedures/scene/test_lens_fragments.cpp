// The fragmenting lens in the scene (lens.model = fragments, procedures/scene/lens_fragments): the
// demo's probe emulsifies and aspirates cells, the lens body's tets follow the removals, nothing
// goes non-finite, and the run is the same on one and two threads.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <filesystem>

#include "components/tets.hpp"
#include "engine/core/error.hpp"
#include "procedures/scene/lens_fragments.hpp"
#include "procedures/scene/scene.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

Scenario fragments_demo() {
  Scenario s = load_scenario(std::filesystem::path(PHACO_SOURCE_DIR) /
                             "data/scenarios/phaco_sculpting_demo.json");
  s.eye.level = 0;
  s.duration_s = 12.0;  // the first passes of the first trench
  s.methods["lens.model"] = "fragments";
  return s;
}

std::unique_ptr<Scene> run_fragments(const Scenario& s, int threads) {
  return test::run_to_end(s, threads);
}

TEST(LensFragments, TheProbeEmulsifiesAndAspiratesAndTheLensStaysFinite) {
  auto scene = run_fragments(fragments_demo(), 1);
  const Entity lens = *scene->body(BodyPart::Lens);
  const LensFragments& lf = scene->world.at<LensFragments>(lens);
  EXPECT_GT(lf.lens.cells_removed, 100u);
  EXPECT_GT(lf.lens.cells_aspirated, 0u) << "the probe's port takes in what reaches it";
  EXPECT_EQ(scene->world.at<Tets>(lens).slots.live_count(), lf.lens.cells.alive_count);
  const auto j = lens_fragments_summary(*scene);
  EXPECT_TRUE(j["finite"].get<bool>());
  EXPECT_GE(j["fragments"].get<uint32_t>(), 1u);
  // Labels cover exactly the alive cells.
  uint32_t labelled = 0;
  for (uint32_t c = 0; c < lf.lens.cells.size(); ++c) {
    EXPECT_EQ(lf.lens.cells.alive[c] != 0, lf.lens.fragments.label[c] != kNoSimplex)
        << "cell " << c;
    labelled += lf.lens.fragments.label[c] != kNoSimplex;
  }
  EXPECT_EQ(labelled, lf.lens.cells.alive_count);
}

TEST(LensFragments, SameOnOneAndTwoThreads) {
  const Scenario s = fragments_demo();
  EXPECT_EQ(state_hash(*run_fragments(s, 1)), state_hash(*run_fragments(s, 2)));
}

TEST(LensFragments, SculptingMethodsDoNotApplyToFragments) {
  Scenario s = fragments_demo();
  s.methods["lens.broadphase"] = "dbvt";
  EXPECT_THROW(build_scene(s, SceneOptions{}), InputError);
  s = fragments_demo();
  s.methods["lens.model"] = "voxels";
  EXPECT_THROW(build_scene(s, SceneOptions{}), InputError);
}

}  // namespace
}  // namespace phaco
