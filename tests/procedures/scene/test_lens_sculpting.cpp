// Phaco-sculpting in the running scene (procedures/scene/lens_sculpting): the divide-and-conquer
// demo sculpts two trenches with a quarter turn of the nucleus between them; the lens stays
// finite, its surface list stays exact, the result does not depend on the thread count, and the
// trench measures come out of the removed tets.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <numbers>
#include <vector>

#include "components/particles.hpp"
#include "components/tets.hpp"
#include "engine/core/error.hpp"
#include "procedures/scene/lens_sculpting.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

Scenario demo(int level) {
  Scenario s = load_scenario(std::filesystem::path(PHACO_SOURCE_DIR) /
                             "data/scenarios/phaco_sculpting_demo.json");
  s.eye.level = level;
  return s;
}

std::unique_ptr<Scene> run_sculpting(const Scenario& s, int threads) {
  return test::run_to_end(s, threads);
}

TEST(LensSculpting, TheDivideAndConquerDemoCutsTwoCrossedTrenchesWithoutNaN) {
  auto scene = run_sculpting(demo(1), 1);
  const Entity lens = *scene->body(BodyPart::Lens);
  const LensSculpting& ls = scene->world.at<LensSculpting>(lens);
  const Particles& p = scene->world.at<Particles>(lens);
  for (size_t i = 0; i < p.x.size(); ++i) {
    ASSERT_TRUE(std::isfinite(p.x[i]) && std::isfinite(p.y[i]) && std::isfinite(p.z[i]))
        << "particle " << i;
  }
  // Removed tets are gone from the scene's table too, and the surface list is exact.
  const Tets& tets = scene->world.at<Tets>(lens);
  EXPECT_EQ(tets.slots.live_count(), ls.topology.alive_count);
  EXPECT_GT(ls.topology.tet_count - ls.topology.alive_count, 500u);
  uint32_t surface = 0;
  for (uint32_t t = 0; t < ls.topology.tet_count; ++t) {
    const bool on = tet_on_surface(ls.topology, t);
    surface += on;
    EXPECT_EQ(on, ls.topology.surface_slot[t] != kNoTet) << "tet " << t;
  }
  EXPECT_EQ(surface, ls.topology.surface.size());
  // Inertia lost exactly m·Σr² of what was removed (seed 000 §5.4), and the nucleus turned.
  double r2 = 0;
  for (const auto& e : ls.removed) r2 += e.centre.x() * e.centre.x() + e.centre.y() * e.centre.y();
  EXPECT_NEAR(ls.rotation.inertia, ls.rotation.inertia0 - ls.rotation.tet_mass_kg * r2,
              1e-9 * ls.rotation.inertia0);
  EXPECT_GT(std::abs(ls.rotation.angle_rad), 1.0)
      << "the push between the trenches turns the nucleus";
  // The scene's particles are the rest shape turned by that angle.
  const double c = std::cos(ls.rotation.angle_rad), s = std::sin(ls.rotation.angle_rad);
  for (size_t i = 0; i < p.x.size(); i += 97) {
    EXPECT_NEAR(p.x[i], c * ls.rest[i].x() - s * ls.rest[i].y(), 1e-4);
    EXPECT_NEAR(p.y[i], s * ls.rest[i].x() + c * ls.rest[i].y(), 1e-4);
  }
  // Two trenches, each about 1.5 tip diameters wide and most of the nucleus deep, crossing near
  // 90°.
  const lens::TrenchReport r = lens_trenches(*scene);
  ASSERT_EQ(r.trenches.size(), 2u);
  for (const auto& t : r.trenches) {
    EXPECT_GT(t.width_mm, 1.2);
    EXPECT_LT(t.width_mm, 2.0);
    EXPECT_GT(t.depth_fraction, 0.6);
    EXPECT_LT(t.depth_fraction, 1.0);
  }
  EXPECT_NEAR(r.crossing_angle_deg, 90.0, 15.0);
  const nlohmann::json j = lens_sculpting_summary(*scene);
  EXPECT_EQ(j["trench_count"].get<size_t>(), 2u);
  EXPECT_EQ(j["strokes"].get<uint32_t>(), 16u);
}

// The expert's first trench and the quarter-turn push that follows it, cut where the probe comes
// out of the trench after the push (the pedal-1 samples down in the trench, z < 1 mm, then the
// first sample with the pedal past 1: the second trench begins).
Scenario expert_push(int level) {
  Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
  s.eye.level = level;
  const auto& track = s.hands.front().track;
  size_t i = 0;
  while (i < track.size() && !(track[i].pedal == 1.0 && track[i].pos.z() < 1.0)) ++i;
  while (i < track.size() && track[i].pedal <= 1.0) ++i;
  EXPECT_LT(i, track.size()) << "the expert pushes in the first trench, then sculpts again";
  if (i < track.size()) s.duration_s = track[i].t;
  return s;
}

// The same push turns the nucleus alike at every mesh level (issue 19): the trench wall cannot
// pass the tip, so the turn is the tip's travel about the axis (a quarter turn and 0.22 rad) less
// the trench's free play, geometry the levels share. What differs between levels is where the
// wall's nearest surviving tet centre lies: up to half a tet spacing behind the sculpted boundary.
// Level 0's spacing is about 0.65 mm (6275 tets): up to 0.33 mm, 12.5 degrees at the tip's 1.5 mm
// from the axis, in the worst case; the tip's sphere meets several centres along the wall, so
// less. Tolerances: 7 degrees over levels 0-3 (0.18 mm of wall), 1.5 degrees over levels 1-3
// (0.04 mm). Measured: 84.0 / 89.2 / 89.0 / 89.8 degrees. The seed's push law (θ = ½·α·Δt² while
// the tip touches a tet) turned the nucleus 83.8 / 89.1 / 109.7 / 110.0 degrees for this push.
TEST(LensSculpting, TheSamePushTurnsTheNucleusAlikeAtEveryLevel) {
  std::vector<double> turn_deg;
  for (int level = 0; level <= 3; ++level) {
    auto scene = run_sculpting(expert_push(level), 2);
    const LensSculpting& ls = scene->world.at<LensSculpting>(*scene->body(BodyPart::Lens));
    turn_deg.push_back(ls.rotation.angle_rad * 180.0 / std::numbers::pi);
    EXPECT_GT(ls.push_frames, 50u) << "level " << level;
  }
  for (size_t level = 0; level < turn_deg.size(); ++level)
    std::printf("level %zu: nucleus turned %.2f deg\n", level, turn_deg[level]);
  const auto [lo, hi] = std::minmax_element(turn_deg.begin(), turn_deg.end());
  EXPECT_LT(*hi - *lo, 7.0) << "degrees between the levels' turns, levels 0-3";
  const auto [lo1, hi1] = std::minmax_element(turn_deg.begin() + 1, turn_deg.end());
  EXPECT_LT(*hi1 - *lo1, 1.5) << "degrees between the levels' turns, levels 1-3";
  for (double t : turn_deg) EXPECT_NEAR(t, 90.0, 7.0) << "a quarter turn, as the expert aims";
}

TEST(LensSculpting, SameResultOnOneAndTwoThreadsAndWithEitherBroadphase) {
  Scenario s = demo(0);
  s.duration_s = 26.0;  // the first trench and the turn
  const std::string one = state_hash(*run_sculpting(s, 1));
  EXPECT_EQ(one, state_hash(*run_sculpting(s, 2)));
  s.methods["lens.broadphase"] = "dbvt";
  EXPECT_EQ(one, state_hash(*run_sculpting(s, 1))) << "the octree and btDbvt find the same tets";
}

TEST(LensSculpting, NoUltrasoundNoRemoval) {
  Scenario s = demo(0);
  for (auto& hand : s.hands)
    for (auto& sample : hand.track) sample.pedal = std::min(sample.pedal, 2.0);
  s.duration_s = 10.0;
  auto scene = run_sculpting(s, 1);
  const LensSculpting& ls = scene->world.at<LensSculpting>(*scene->body(BodyPart::Lens));
  EXPECT_EQ(ls.topology.alive_count, ls.topology.tet_count);
  EXPECT_EQ(ls.strokes, 0u);
}

TEST(LensSculpting, UnknownMethodsAndBodiesAreNamed) {
  Scenario s = demo(0);
  s.methods["lens.broadphase"] = "kd_tree";
  try {
    run_sculpting(s, 1);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("lens.broadphase"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("octree, dbvt"), std::string::npos) << e.what();
  }
  Scenario rhexis = load_scenario(std::filesystem::path(PHACO_SOURCE_DIR) /
                                  "data/scenarios/capsulorhexis_demo.json");
  rhexis.methods["lens.narrowphase"] = "exact_gjk";
  EXPECT_THROW(run_sculpting(rhexis, 1), InputError)
      << "the capsulorhexis scene has no tetrahedral lens";
}

}  // namespace
}  // namespace phaco
