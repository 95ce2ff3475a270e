// Implicit Euler on an active node set: sleeping particles stay put, a local disturbance gives the
// full-set answer inside the set, and the work (unknowns, nonzeros) follows the set, not the mesh.
// Also: warm start, the two CG operators, determinism across thread counts.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>

#include "systems/active_nodes/active_nodes.hpp"
#include "systems/springs/springs.hpp"
#include "tests/systems/deform/implicit_fixtures.hpp"

namespace phaco {
namespace {

using deform::ImplicitCache;
using implicit_test::Body;
using implicit_test::make_grid;

constexpr double kFrameStep = 1.0 / 120.0;

uint32_t centre(int n) {
  return static_cast<uint32_t>((n / 2) * n + n / 2);
}

// The centre node grasped (scripted) and pulled up at 10 mm/s; the set is its k-hop ball.
void grasp_centre(Body& b, int n, uint32_t hops) {
  const uint32_t g = centre(n);
  b.particles.kind[g] = ParticleKind::Scripted;
  b.particles.vz[g] = 10.0f;
  const auto graph = springs::build_spring_graph(b.springs, b.particles.slots.size());
  active_nodes::ActiveSet set;
  const uint32_t seeds[] = {g};
  active_nodes::update_active_set(graph, seeds, hops, {}, set);
  b.active = set.particles;
  b.active_springs = set.springs;
}

// The tool moves the grasped node; the membrane follows.
void step(Body& b, double dt, ImplicitCache& cache, int n) {
  const uint32_t g = centre(n);
  b.particles.z[g] += static_cast<float>(dt * b.particles.vz[g]);
  auto m = b.membrane();
  deform::implicit_euler_step(m, dt, cache);
}

// A moderately stiff patch (k·dt²/m ≈ 1 at dt = 1/120 s): an implicit step's response to a local
// pull decays over a few hops, so a 5-hop set holds nearly all of it.
Body soft_patch(int n) {
  return make_grid(n, 0.2, 5e-5, {.sheet_modulus_mn_mm = 0.5, .prestretch = 0.05});
}

TEST(ImplicitActiveSet, SleepingParticlesStayAndTheSetMatchesTheFullStep) {
  const int n = 31;
  Body full = soft_patch(n), local = soft_patch(n);
  grasp_centre(full, n, 5);
  grasp_centre(local, n, 5);
  full.active.clear(), full.active_springs.clear();
  const Particles before = local.particles;
  ImplicitCache cf, cl;
  for (int s = 0; s < 3; ++s) step(full, kFrameStep, cf, n), step(local, kFrameStep, cl, n);

  std::vector<uint8_t> in_set(n * n, 0);
  for (uint32_t i : local.active) in_set[i] = 1;
  double max_motion = 0.0, max_difference = 0.0, outside_full = 0.0;
  for (uint32_t i = 0; i < local.particles.slots.size(); ++i) {
    if (i == centre(n)) continue;
    const double dz_full = full.particles.z[i] - before.z[i];
    if (!in_set[i]) {
      EXPECT_EQ(local.particles.x[i], before.x[i]);
      EXPECT_EQ(local.particles.y[i], before.y[i]);
      EXPECT_EQ(local.particles.z[i], before.z[i]);
      EXPECT_EQ(local.particles.vz[i], before.vz[i]);
      outside_full = std::max(outside_full, std::fabs(dz_full));
      continue;
    }
    max_motion = std::max(max_motion, std::fabs(dz_full));
    max_difference =
        std::max(max_difference, std::fabs(double(local.particles.z[i]) - full.particles.z[i]));
  }
  std::printf(
      "[ figures  ] 5-hop set of %zu: max motion %.4g mm, max difference to the full step %.3g mm "
      "(%.2f %%); full-step motion outside the set %.3g mm\n",
      local.active.size(), max_motion, max_difference, 100 * max_difference / max_motion,
      outside_full);
  EXPECT_GT(max_motion, 0.05);
  EXPECT_LT(max_difference, 0.03 * max_motion);
}

TEST(ImplicitActiveSet, WorkFollowsTheSetNotTheMesh) {
  ImplicitCache small_cache, large_cache;
  Body small = soft_patch(21), large = soft_patch(81);
  grasp_centre(small, 21, 5);
  grasp_centre(large, 81, 5);
  step(small, kFrameStep, small_cache, 21);
  step(large, kFrameStep, large_cache, 81);
  // One diagonal per square: the 5-hop ball is a hexagon of 3k² + 3k + 1 = 91 nodes, the same on
  // both meshes; the grasped node is not an unknown.
  EXPECT_EQ(small.active.size(), 91u);
  EXPECT_EQ(small_cache.stats.unknowns, small.active.size() - 1);
  EXPECT_EQ(small_cache.stats.unknowns, large_cache.stats.unknowns);
  EXPECT_EQ(small_cache.stats.nonzeros, large_cache.stats.nonzeros);
  EXPECT_EQ(small_cache.stats.springs, large_cache.stats.springs);
  EXPECT_LT(large_cache.stats.unknowns * 40u, 79u * 79u);

  Body whole = soft_patch(81);
  ImplicitCache whole_cache;
  auto m = whole.membrane();
  deform::implicit_euler_step(m, kFrameStep, whole_cache);
  EXPECT_EQ(whole_cache.stats.unknowns, 79u * 79u);
  std::printf(
      "[ figures  ] 81×81 patch: %u unknowns / %llu nonzeros with a 5-hop set, %u / %llu without\n",
      large_cache.stats.unknowns, static_cast<unsigned long long>(large_cache.stats.nonzeros),
      whole_cache.stats.unknowns, static_cast<unsigned long long>(whole_cache.stats.nonzeros));
}

TEST(ImplicitActiveSet, PatternIsBuiltOncePerSet) {
  Body b = soft_patch(21);
  grasp_centre(b, 21, 4);
  ImplicitCache cache;
  for (int s = 0; s < 5; ++s) step(b, kFrameStep, cache, 21);
  EXPECT_EQ(cache.stats.pattern_builds, 1u);
  grasp_centre(b, 21, 5);  // a larger set
  step(b, kFrameStep, cache, 21);
  EXPECT_EQ(cache.stats.pattern_builds, 2u);
}

// Two similar steps: the same frame stepped twice from the same state (as when the guard retries
// a step). The second solve starts from the first one's Δv and needs (almost) no iterations; from
// zero it needs them all. Along a trajectory the saving is small (docs/implicit_and_active.md).
TEST(ImplicitEuler, WarmStartReducesIterations) {
  const int n = 41;
  Body b = soft_patch(n);
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  ImplicitCache warm, cold;
  warm.settings.cg_tolerance = cold.settings.cg_tolerance = 1e-8;
  cold.settings.warm_start = false;
  for (int s = 0; s < 4; ++s) {
    auto m = b.membrane();
    deform::implicit_euler_step(m, kFrameStep, warm);
  }
  const Particles state = b.particles;
  auto m = b.membrane();
  deform::implicit_euler_step(m, kFrameStep, warm);
  const int first = warm.stats.cg_iterations;
  b.particles = state;
  deform::implicit_euler_step(m, kFrameStep, warm);
  const int second = warm.stats.cg_iterations;
  b.particles = state;
  deform::implicit_euler_step(m, kFrameStep, cold);
  std::printf(
      "[ figures  ] CG iterations: first solve %d, same step warm-started %d, from zero %d\n",
      first, second, cold.stats.cg_iterations);
  EXPECT_GT(first, 5);
  EXPECT_LT(second, cold.stats.cg_iterations);
  EXPECT_LE(second, 1);
}

TEST(ImplicitEuler, AssembledAndMatrixFreeOperatorsAgree) {
  const int n = 25;
  Body a = soft_patch(n), f = soft_patch(n);
  grasp_centre(a, n, 6), grasp_centre(f, n, 6);
  ImplicitCache ca, cf;
  ca.settings.cg_tolerance = cf.settings.cg_tolerance = 1e-12;
  ca.settings.cg_operator = deform::CgOperator::Assembled;
  cf.settings.cg_operator = deform::CgOperator::MatrixFree;
  for (int s = 0; s < 4; ++s) step(a, kFrameStep, ca, n), step(f, kFrameStep, cf, n);
  EXPECT_EQ(ca.stats.cg_iterations > 0, true);
  double worst = 0.0;
  for (uint32_t i = 0; i < a.particles.slots.size(); ++i)
    worst = std::max(worst, double(std::fabs(a.particles.z[i] - f.particles.z[i])));
  EXPECT_LT(worst, 1e-5);
}

TEST(ImplicitEuler, IdenticalForOneTwoAndFourThreads) {
  uint64_t hashes[3];
  int k = 0;
  for (int threads : {1, 2, 4}) {
    tbb::task_arena arena(threads);
    arena.execute([&] {
      Body b = soft_patch(31);
      grasp_centre(b, 31, 6);
      ImplicitCache cache;
      for (int s = 0; s < 4; ++s) step(b, kFrameStep, cache, 31);
      hashes[k++] = implicit_test::hash_state(b.particles);
    });
  }
  EXPECT_EQ(hashes[0], hashes[1]);
  EXPECT_EQ(hashes[0], hashes[2]);
}

}  // namespace
}  // namespace phaco
