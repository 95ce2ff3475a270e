#include <gtest/gtest.h>

#include "systems/grasp/grasp.hpp"

namespace phaco {
namespace {

// Three free particles on the x axis at 0, 1, 2 mm and an anchored one at 0.5.
Particles row() {
  Particles p;
  table_append(p, 4);
  for (uint32_t i = 0; i < 3; ++i) p.x[i] = static_cast<float>(i);
  p.x[3] = 0.5f;
  p.kind[3] = ParticleKind::Anchored;
  return p;
}

TEST(Grasp, NearestFreeParticleWithinRadius) {
  const Particles p = row();
  EXPECT_EQ(grasp::nearest_particle(p, {0.9, 0.1, 0}, 0.3), 1u);
  EXPECT_EQ(grasp::nearest_particle(p, {0.5, 0, 0}, 0.3), kInvalidIndex)
      << "anchored ones are never taken";
  EXPECT_EQ(grasp::nearest_particle(p, {0.5, 0, 0}, 0.3, ParticleKind::Anchored), 3u);
  EXPECT_EQ(grasp::nearest_particle(p, {5, 0, 0}, 0.3), kInvalidIndex);
}

TEST(Grasp, CloseHoldMoveAndRelease) {
  Particles p = row();
  grasp::GraspState s;
  const double dt = 0.01;
  EXPECT_FALSE(grasp::update_grasp(s, p, {1.1, 0, 0}, 0.2, dt).grasped) << "grip below close_at";
  const auto taken = grasp::update_grasp(s, p, {1.1, 0, 0}, 0.8, dt);
  EXPECT_TRUE(taken.grasped);
  ASSERT_TRUE(s.holding());
  EXPECT_EQ(s.particle, 1u);
  EXPECT_EQ(p.kind[1], ParticleKind::Scripted);
  EXPECT_FLOAT_EQ(p.x[1], 1.1f) << "the held particle sits at the tip";

  grasp::update_grasp(s, p, {1.1, 0, 0.5}, 0.4,
                      dt);  // grip between open_at and close_at: still held
  EXPECT_TRUE(s.holding());
  EXPECT_FLOAT_EQ(p.z[1], 0.5f);
  EXPECT_NEAR(p.vz[1], 50.0, 1e-3) << "velocity follows the tool: 0.5 mm in 10 ms";

  const auto let_go = grasp::update_grasp(s, p, {1.1, 0, 0.6}, 0.1, dt);
  EXPECT_TRUE(let_go.released);
  EXPECT_FALSE(s.holding());
  EXPECT_EQ(p.kind[1], ParticleKind::Free);
  EXPECT_NEAR(p.vz[1], 10.0, 1e-3) << "released with the tool's velocity";
}

TEST(Grasp, ClosingOnNothingIsAMiss) {
  Particles p = row();
  grasp::GraspState s;
  const auto ev = grasp::update_grasp(s, p, {10, 0, 0}, 1.0, 0.01);
  EXPECT_TRUE(ev.missed);
  EXPECT_FALSE(s.holding());
  // Staying closed does not grab what comes near later: a grasp needs the forceps to close.
  EXPECT_FALSE(grasp::update_grasp(s, p, {1, 0, 0}, 1.0, 0.01).grasped);
  EXPECT_FALSE(s.holding());
}

TEST(Grasp, RemovedParticleIsLetGo) {
  Particles p = row();
  grasp::GraspState s;
  grasp::update_grasp(s, p, {2, 0, 0}, 1.0, 0.01);
  ASSERT_TRUE(s.holding());
  table_remove(p, 2);
  grasp::update_grasp(s, p, {2, 0, 0}, 1.0, 0.01);
  EXPECT_FALSE(s.holding());
}

}  // namespace
}  // namespace phaco
