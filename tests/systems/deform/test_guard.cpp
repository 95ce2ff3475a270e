// The divergence guard: every integrator driven past its limit recovers without NaN, and non-finite
// input is survived.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "tests/engine/schedule/alloc_counter.hpp"
#include "tests/systems/deform/deform_fixtures.hpp"

namespace phaco {
namespace {

using deform_test::Body;

constexpr Integrator kAll[] = {Integrator::ExplicitEuler,   Integrator::SymplecticEuler,
                               Integrator::SemiImplicit001, Integrator::Xpbd,
                               Integrator::ImplicitEuler,   Integrator::ImplicitPredictor};

// A pinned patch whose highest mode has ω_max ≈ √(2·Σk/m); dt three times symplectic Euler's limit.
TEST(Guard, SymplecticPastItsLimitRecoversBySubsteps) {
  Body b = deform_test::make_grid(9, 0.5, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
  b.dynamics.integrator = Integrator::SymplecticEuler;
  b.loads.push_back({deform_test::centre_particle(b), 0.0f, 0.0f, -0.02f});
  const double omega_max =
      std::sqrt(2.0 * springs::max_stiffness_over_mass(b.springs, b.particles));
  const double dt = 3.0 * 2.0 / omega_max;
  deform::DeformState st;
  for (int s = 0; s < 50; ++s) {
    deform::Membrane m = b.membrane();
    const auto report = deform::step(m, dt, st);
    ASSERT_TRUE(deform_test::all_finite(b.particles)) << "step " << s;
    EXPECT_FALSE(report.held);
  }
  EXPECT_GE(st.status.divergences, 1u);
  EXPECT_EQ(st.status.fallbacks, 0u);  // substeps were enough
  EXPECT_EQ(st.status.in_use, Integrator::SymplecticEuler);
  EXPECT_GE(st.status.substeps_in_use, 4);   // 3× the limit needs at least 4 substeps
  EXPECT_LE(st.status.substeps_in_use, 16);  // and the guard does not overshoot wildly
  EXPECT_LT(deform_test::max_speed(b.particles), b.dynamics.max_speed_mm_s);
}

// Every integrator, with a speed bound the motion must exceed (a tool yanks one particle 2 mm in
// one frame): the guard rolls back, substeps, falls back, and at worst holds the body still. The
// state stays finite, under the bound, and the status counts what happened.
TEST(Guard, EveryIntegratorDrivenPastItsBoundRecoversWithoutNaN) {
  for (const Integrator integrator : kAll) {
    Body b = deform_test::make_grid(9, 0.5, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
    b.dynamics.integrator = integrator;
    b.dynamics.max_speed_mm_s = 5.0f;
    const uint32_t tool = deform_test::centre_particle(b);
    b.particles.kind[tool] = ParticleKind::Scripted;
    deform::DeformState st;
    deform::Membrane m0 = b.membrane();
    deform::step(m0, 1e-3, st);   // settle the bookkeeping at rest
    b.particles.z[tool] += 2.0f;  // the yank
    for (int s = 0; s < 5; ++s) {
      deform::Membrane m = b.membrane();
      const auto report = deform::step(m, 1e-3, st);
      ASSERT_TRUE(deform_test::all_finite(b.particles)) << to_string(integrator) << " step " << s;
      if (s == 0) {
        EXPECT_TRUE(report.diverged) << to_string(integrator);
      }
      for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
        if (b.particles.kind[i] != ParticleKind::Free) continue;
        ASSERT_LE(std::hypot(b.particles.vx[i], b.particles.vy[i], b.particles.vz[i]), 5.0f)
            << to_string(integrator) << " step " << s;
      }
    }
    EXPECT_GE(st.status.divergences, 1u) << to_string(integrator);
    EXPECT_EQ(st.status.steps, 6u);
  }
}

TEST(Guard, NonFiniteLoadIsIgnoredAndCounted) {
  Body b = deform_test::make_grid(7, 0.5, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
  b.dynamics.integrator = Integrator::SymplecticEuler;
  const uint32_t centre = deform_test::centre_particle(b);
  b.loads.push_back({centre, std::numeric_limits<float>::quiet_NaN(), 0.0f, 0.0f});
  b.loads.push_back({centre, 0.0f, std::numeric_limits<float>::infinity(), 0.0f});
  b.loads.push_back({centre, 0.0f, 0.0f, -0.01f});  // a good one still acts
  deform::DeformState st;
  for (int s = 0; s < 10; ++s) {
    deform::Membrane m = b.membrane();
    const auto report = deform::step(m, 1e-5, st);
    EXPECT_EQ(report.rejected_loads, 2u);
  }
  EXPECT_EQ(st.rejected_loads, 20u);
  EXPECT_TRUE(deform_test::all_finite(b.particles));
  EXPECT_LT(b.particles.z[centre], 0.0f);
  EXPECT_EQ(st.status.divergences, 0u);
}

TEST(Guard, NonFinitePositionAndVelocityAreRepaired) {
  for (const Integrator integrator : kAll) {
    Body b = deform_test::make_grid(7, 0.5, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
    b.dynamics.integrator = integrator;
    deform::DeformState st;
    for (int s = 0; s < 3; ++s) {
      deform::Membrane m = b.membrane();
      deform::step(m, 1e-5, st);
    }
    const uint32_t centre = deform_test::centre_particle(b);
    const float x_good = b.particles.x[centre];
    b.particles.x[centre] = std::numeric_limits<float>::quiet_NaN();
    b.particles.vy[centre + 1] = -std::numeric_limits<float>::infinity();
    deform::Membrane m = b.membrane();
    const auto report = deform::step(m, 1e-5, st);
    EXPECT_EQ(report.repaired_particles, 2u) << to_string(integrator);
    EXPECT_TRUE(deform_test::all_finite(b.particles)) << to_string(integrator);
    EXPECT_NEAR(b.particles.x[centre], x_good, 1e-3) << to_string(integrator);
    EXPECT_EQ(st.repaired_particles, 2u);
  }
}

// After the first step, stepping (including a rolled-back, substepped recovery) does not allocate.
TEST(Guard, StepsAfterTheFirstDoNotAllocate) {
  if (!test::allocation_counting_available())
    GTEST_SKIP() << "allocation counting is off under ASan";
  for (const Integrator integrator : {Integrator::ExplicitEuler, Integrator::SymplecticEuler,
                                      Integrator::SemiImplicit001, Integrator::Xpbd}) {
    Body b = deform_test::make_capsule(2, 20.0, 0.02);
    b.dynamics.integrator = integrator;
    b.dynamics.mass_scale = 1.0e4f;
    b.dynamics.damping_per_s = 50.0f;
    b.loads.push_back({deform_test::centre_particle(b), 0.0f, 0.0f, -0.05f});
    b.environment.has_lens = b.environment.has_cornea = true;
    deform::DeformState st;
    const double omega_max =
        std::sqrt(2.0 * springs::max_stiffness_over_mass(b.springs, b.particles) / 1.0e4);
    deform::Membrane m = b.membrane();
    deform::step(m, 0.5 / omega_max, st);  // warm-up: sizes the scratch
    test::start_counting_allocations();
    for (int s = 0; s < 5; ++s) deform::step(m, 0.5 / omega_max, st);
    deform::step(m, 6.0 / omega_max, st);  // past the explicit limits: rollback and substeps
    test::stop_counting_allocations();
    EXPECT_EQ(test::allocations_counted(), 0) << to_string(integrator);
  }
}

}  // namespace
}  // namespace phaco
