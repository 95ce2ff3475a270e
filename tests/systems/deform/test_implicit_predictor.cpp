// Seed 004's approximate implicit predictor: stable at the frame step with the real capsule
// material, close to implicit Euler for small displacements, factorisation computed once and
// reused until something it depends on changes.
#include <gtest/gtest.h>

#include <chrono>
#include <cmath>

#include "tests/systems/deform/implicit_fixtures.hpp"

namespace phaco {
namespace {

using deform::ImplicitCache;
using implicit_test::Body;
using implicit_test::make_capsule;
using implicit_test::make_grid;

constexpr double kFrameStep = 1.0 / 120.0;

TEST(ImplicitPredictor, StableAtFrameStepWithCapsuleMaterial) {
  for (int level : {0, 1}) {
    Body b = make_capsule(level, 2000.0, 0.02);
    b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i)
      if (b.particles.kind[i] == ParticleKind::Free) b.particles.vz[i] = -50.0f;
    ImplicitCache cache;
    double energy = implicit_test::total_energy(b);
    for (int s = 0; s < 60; ++s) {
      auto m = b.membrane();
      deform::implicit_predictor_step(m, kFrameStep, cache);
      ASSERT_TRUE(implicit_test::all_finite(b.particles)) << "level " << level << " step " << s;
      const double e = implicit_test::total_energy(b);
      EXPECT_LE(e, energy + 1e-9 * std::fabs(energy) + 1e-12) << "level " << level << " step " << s;
      energy = e;
    }
    double max_speed = 0.0;
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i)
      max_speed = std::max(max_speed, double(std::fabs(b.particles.vz[i])));
    EXPECT_LT(max_speed, 1.0) << "the kick has died out";
    EXPECT_EQ(cache.stats.precomputations, 1u);
  }
}

// A patch whose centre is lifted by `pull_mm` and released: the largest difference between the
// predictor's and implicit Euler's z over 30 frames; `relaxed` gets implicit Euler's final centre
// z.
double predictor_vs_implicit(double pull_mm, deform::PredictorStiffness stiffness,
                             double* relaxed) {
  const int n = 21;
  const uint32_t g = (n / 2) * n + n / 2;
  Body bodies[2] = {make_grid(n, 0.2, 5e-5, {.sheet_modulus_mn_mm = 0.5, .prestretch = 0.05}),
                    make_grid(n, 0.2, 5e-5, {.sheet_modulus_mn_mm = 0.5, .prestretch = 0.05})};
  ImplicitCache caches[2];
  caches[0].settings.cg_tolerance = 1e-10;
  caches[1].settings.predictor_stiffness = stiffness;
  for (Body& b : bodies) b.particles.z[g] = static_cast<float>(pull_mm);
  double worst = 0.0;
  for (int s = 0; s < 30; ++s) {
    auto m0 = bodies[0].membrane();
    deform::implicit_euler_step(m0, kFrameStep, caches[0]);
    auto m1 = bodies[1].membrane();
    deform::implicit_predictor_step(m1, kFrameStep, caches[1]);
    for (uint32_t i = 0; i < bodies[0].particles.slots.size(); ++i)
      worst =
          std::max(worst, double(std::fabs(bodies[0].particles.z[i] - bodies[1].particles.z[i])));
  }
  *relaxed = bodies[0].particles.z[g];
  return worst;
}

TEST(ImplicitPredictor, MatchesImplicitEulerForSmallDisplacements) {
  for (double pull : {0.002, 0.02}) {
    double relaxed = 0.0;
    const double frozen =
        predictor_vs_implicit(pull, deform::PredictorStiffness::FrozenJacobian, &relaxed);
    const double isotropic =
        predictor_vs_implicit(pull, deform::PredictorStiffness::Isotropic, &relaxed);
    std::printf(
        "[ figures  ] pull %.3g mm released: implicit Euler's centre at %.3g mm after 30 frames; "
        "largest "
        "difference to it: frozen Jacobian %.3g mm (%.2f %% of the pull), isotropic %.3g mm (%.1f "
        "%%)\n",
        pull, relaxed, frozen, 100 * frozen / pull, isotropic, 100 * isotropic / pull);
    EXPECT_LT(relaxed, 0.5 * pull);  // the pull did relax: the comparison covers real motion
    EXPECT_LT(frozen, (pull < 0.01 ? 0.01 : 0.1) * pull);
    EXPECT_GT(isotropic, 5 * frozen);  // the isotropic filter lags out of plane (see implicit.hpp)
  }
}

TEST(ImplicitPredictor, FactorisationIsReusedUntilItsInputsChange) {
  Body b = make_grid(15, 0.2, 5e-5, {.sheet_modulus_mn_mm = 0.5, .prestretch = 0.05});
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  ImplicitCache cache;
  auto run = [&](double dt, int steps) {
    for (int s = 0; s < steps; ++s) {
      auto m = b.membrane();
      deform::implicit_predictor_step(m, dt, cache);
    }
  };
  run(kFrameStep, 10);
  EXPECT_EQ(cache.stats.precomputations, 1u);
  EXPECT_EQ(cache.stats.predictor_steps, 10u);
  EXPECT_EQ(cache.stats.predictor_unknowns, 13u * 13u);
  run(kFrameStep / 2, 1);  // a new dt (substeps)
  EXPECT_EQ(cache.stats.precomputations, 2u);
  b.particles.kind[7 * 15 + 7] = ParticleKind::Scripted;  // a grasp
  run(kFrameStep / 2, 3);
  EXPECT_EQ(cache.stats.precomputations, 3u);
  EXPECT_EQ(cache.stats.predictor_unknowns, 13u * 13u - 1);
  cache.invalidate();  // a cut or tear
  run(kFrameStep / 2, 1);
  EXPECT_EQ(cache.stats.precomputations, 4u);
}

}  // namespace
}  // namespace phaco
