// Every scene's systems touch only what they declare (issue 17 item 4): each drill's scripted
// expert runs with the executor's access check on (engine/core/access_scope.hpp), so a World
// lookup of an undeclared component, or two systems racing on one, fails the run with the
// system's and the component's names. Release builds run the check only here; debug builds run
// it in every scene.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>

#include "procedures/scene/haptic_publish.hpp"
#include "procedures/scene/scene.hpp"
#include "tests/support/sanitizers.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

// A haptic runtime with no device, so the scene also runs its publish system.
class NullPort final : public HapticPort {
 public:
  bool newest_pose(Hand, ToolPose&) override { return false; }
  HapticModel& model_slot() override { return slot; }
  void publish_model() override {}
  HapticModel slot;
};

struct AccessCase {
  const char* file;
  const char* lens_model;  // methods["lens.model"], or null
  double seconds;          // how much of the drill to run (Release)
};

std::ostream& operator<<(std::ostream& os, const AccessCase& c) {
  return os << c.file
            << (c.lens_model ? std::string(" lens.model=") + c.lens_model : std::string());
}

class SceneAccess : public ::testing::TestWithParam<AccessCase> {};

TEST_P(SceneAccess, SystemsTouchOnlyWhatTheyDeclare) {
  const AccessCase& c = GetParam();
  Scenario s = test::repo_scenario(c.file);
  if (c.lens_model) s.methods["lens.model"] = c.lens_model;
  NullPort port;
  SceneOptions o;
  o.threads = 2;
  o.cache_dir = test::scene_cache_dir();
  o.haptics = &port;
  o.access_check = AccessCheck::On;
  auto scene = build_scene(s, o);
  ASSERT_TRUE(scene->executor->checks_access());
  const double seconds =
      test::kUnderAsan ? std::min(c.seconds, 2.0) : std::min(c.seconds, s.duration_s);
  const auto frames = static_cast<uint64_t>(std::llround(seconds / s.dt_s));
  for (uint64_t f = 0; f < frames; ++f) ASSERT_NO_THROW(step(*scene)) << "frame " << f;
  EXPECT_EQ(scene->frame, frames);
}

// The capsulorhexis expert's 11 s hold every cut, tear, grasp and release; the sculpting runs
// cover both trenches' first passes and the turn; the incision the whole keratome stroke; the
// nucleus removal its first crack and the first quadrant's hold.
INSTANTIATE_TEST_SUITE_P(
    Drills, SceneAccess,
    ::testing::Values(AccessCase{"capsulorhexis_expert.json", nullptr, 11.0},
                      AccessCase{"corneal_incision_expert.json", nullptr, 3.0},
                      AccessCase{"phaco_sculpting_expert.json", nullptr, 30.0},
                      AccessCase{"phaco_sculpting_demo.json", "fragments", 6.0},
                      AccessCase{"nucleus_removal_expert.json", nullptr, 13.0}));

}  // namespace
}  // namespace phaco
