// Explicit, symplectic, seed-001 and XPBD integrators against analytic and cross-method references.
#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <cmath>
#include <numbers>

#include "tests/systems/deform/deform_fixtures.hpp"

namespace phaco {
namespace {

using deform_test::Body;

constexpr double kK = 1.0;                    // mN/mm
constexpr double kMass = 1e-3;                // kg
const double kOmega = std::sqrt(kK / kMass);  // 31.6 rad/s

// Oscillator energy of the spring-mass (extension u = x − 1), µJ.
double oscillator_energy(const Body& b) {
  const double u = double{b.particles.x[1]} - 1.0, v = b.particles.vx[1];
  return 0.5 * kMass * v * v + 0.5 * kK * u * u;
}

deform::Motion run_one(Body& b, double dt, Integrator integrator, deform::DeformState& st) {
  deform::Membrane m = b.membrane();
  return deform::integrate_once(m, dt, integrator, st);
}

TEST(SpringMass, SymplecticEulerKeepsTheAnalyticPeriodAndBoundedEnergy) {
  Body b = deform_test::make_spring_mass(kK, kMass, 0.01);
  deform::DeformState st;
  const double dt = 0.05 / kOmega, period = 2 * std::numbers::pi / kOmega;
  const double e0 = oscillator_energy(b);
  double e_min = e0, e_max = e0, prev_u = 0.01, last_crossing = -1, first_crossing = -1;
  int crossings = 0;
  for (int s = 1; s * dt < 5 * period; ++s) {
    run_one(b, dt, Integrator::SymplecticEuler, st);
    const double u = double{b.particles.x[1]} - 1.0, e = oscillator_energy(b);
    e_min = std::min(e_min, e), e_max = std::max(e_max, e);
    if (prev_u > 0 && u <= 0) {  // downward zero crossing, interpolated
      const double t = (s - 1 + prev_u / (prev_u - u)) * dt;
      if (first_crossing < 0) first_crossing = t;
      last_crossing = t, ++crossings;
    }
    prev_u = u;
  }
  ASSERT_GE(crossings, 4);
  const double measured = (last_crossing - first_crossing) / (crossings - 1);
  // Symplectic Euler's frequency is (2/dt)·asin(ω·dt/2): 1e-4 relative at ω·dt = 0.05.
  EXPECT_NEAR(measured / period, 1.0, 2e-3);
  // Energy oscillates within O(ω·dt) and does not drift.
  EXPECT_LT(e_max / e0, 1.0 + 0.05);
  EXPECT_GT(e_min / e0, 1.0 - 0.05);
}

TEST(SpringMass, ExplicitEulerGainsOnePlusOmegaSquaredDtSquaredPerStep) {
  for (const double omega_dt : {0.02, 0.1, 0.5}) {
    Body b = deform_test::make_spring_mass(kK, kMass, 0.01);
    deform::DeformState st;
    const double dt = omega_dt / kOmega, factor = 1.0 + omega_dt * omega_dt;
    const int steps = static_cast<int>(std::ceil(std::log(4.0) / std::log(factor)));
    const double e0 = oscillator_energy(b);
    for (int s = 0; s < steps; ++s) run_one(b, dt, Integrator::ExplicitEuler, st);
    const double per_step = std::log(oscillator_energy(b) / e0) / steps;
    EXPECT_NEAR(per_step / std::log(factor), 1.0, 1e-3) << "omega*dt " << omega_dt;
  }
}

// For one degree of freedom the seed-001 scheme and XPBD are exactly backward Euler, whose
// oscillator energy falls by 1/(1 + ω²dt²) per step — at any dt.
TEST(SpringMass, Seed001AndXpbdAreBackwardEulerOnOneSpring) {
  for (const Integrator integrator : {Integrator::SemiImplicit001, Integrator::Xpbd}) {
    for (const double omega_dt : {0.1, 1.0, 10.0}) {
      Body b = deform_test::make_spring_mass(kK, kMass, 0.01);
      deform::DeformState st;
      const double dt = omega_dt / kOmega;
      const double e0 = oscillator_energy(b);
      const int steps = 3;
      for (int s = 0; s < steps; ++s) run_one(b, dt, integrator, st);
      const double per_step = std::pow(oscillator_energy(b) / e0, 1.0 / steps);
      EXPECT_NEAR(per_step * (1.0 + omega_dt * omega_dt), 1.0, 2e-3)
          << to_string(integrator) << " omega*dt " << omega_dt;
    }
  }
}

// A pinned, pre-tensioned patch sagging under gravity: every explicit-family method at a small dt
// reaches the same static equilibrium, and that state is one (residual force ≪ weight).
TEST(PinnedPatch, ExplicitMethodsAgreeOnTheStaticSag) {
  constexpr double kNodeMass = 1e-7, kDt = 5e-6, kDuration = 0.06;
  std::vector<double> sags;
  for (const Integrator integrator : {Integrator::ExplicitEuler, Integrator::SymplecticEuler,
                                      Integrator::SemiImplicit001, Integrator::Xpbd}) {
    Body b =
        deform_test::make_grid(11, 0.5, kNodeMass, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.1});
    b.dynamics.integrator = integrator;
    b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
    b.dynamics.damping_per_s = 900.0f;
    deform::DeformState st;
    st.xpbd.iterations = 4;
    const uint32_t centre = deform_test::centre_particle(b);
    for (int s = 0; s * kDt < kDuration; ++s) {
      deform::Membrane m = b.membrane();
      const auto report = deform::step(m, kDt, st);
      ASSERT_FALSE(report.diverged) << to_string(integrator) << " step " << s;
    }
    // Residual: spring + gravity force on the free particles, without damping.
    b.dynamics.damping_per_s = 0.0f;
    deform::Membrane m = b.membrane();
    deform::compute_forces(m);
    double residual = 0.0;
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
      if (b.particles.kind[i] != ParticleKind::Free) continue;
      residual =
          std::max(residual, double{std::hypot(b.forces.fx[i], b.forces.fy[i], b.forces.fz[i])});
    }
    EXPECT_LT(residual, 1e-2 * kNodeMass * 9810.0) << to_string(integrator);
    sags.push_back(-b.particles.z[centre]);
  }
  ASSERT_GT(sags[1], 1e-3);  // it did sag (mm)
  for (size_t k = 0; k < sags.size(); ++k)
    EXPECT_NEAR(sags[k] / sags[1], 1.0, 5e-3) << "method " << k;
}

double momentum(const Particles& p, int axis) {
  const std::vector<float>& v = axis == 0 ? p.vx : axis == 1 ? p.vy : p.vz;
  double sum = 0.0;
  for (uint32_t i = 0; i < p.slots.size(); ++i) sum += double{v[i]} / p.inv_mass[i];
  return sum;
}

// A free body (no anchors, gravity, damping or glue): springs only exchange momentum.
TEST(FreeBody, ExplicitSymplecticAndXpbdConserveMomentum) {
  for (const Integrator integrator :
       {Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::Xpbd}) {
    Body b = deform_test::make_grid(6, 1.0, 1e-3, {.sheet_modulus_mn_mm = 1.0}, /*pinned=*/false);
    double scale = 0.0;
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
      b.particles.vx[i] = std::sin(1.7f * i), b.particles.vy[i] = std::cos(2.3f * i),
      b.particles.vz[i] = std::sin(0.9f * i + 1);
      scale += std::hypot(b.particles.vx[i], b.particles.vy[i], b.particles.vz[i]) /
               b.particles.inv_mass[i];
    }
    const double p0[3] = {momentum(b.particles, 0), momentum(b.particles, 1),
                          momentum(b.particles, 2)};
    deform::DeformState st;
    for (int s = 0; s < 200; ++s) run_one(b, 0.002, integrator, st);
    for (int a = 0; a < 3; ++a)
      EXPECT_NEAR(momentum(b.particles, a), p0[a], 1e-5 * scale) << to_string(integrator);
  }
}

// The seed-001 scheme's price: the diagonal implicit velocity drags every motion, a rigid
// translation included, by 1/(1 + dt²·κ_i/m) per step.
TEST(FreeBody, Seed001DragsRigidTranslationByItsDiagonal) {
  Body b = deform_test::make_grid(5, 1.0, 1e-3, {.sheet_modulus_mn_mm = 1.0}, /*pinned=*/false);
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i) b.particles.vx[i] = 1.0f;
  deform::DeformState st;
  const double dt = 0.01;
  run_one(b, dt, Integrator::SemiImplicit001, st);
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
    const double expected = 1.0 / (1.0 + dt * dt * st.axial_stiffness[i] * b.particles.inv_mass[i]);
    EXPECT_NEAR(b.particles.vx[i], expected, 1e-6);
    EXPECT_LT(b.particles.vx[i], 1.0f);
  }
}

// Same bits for 1, 2 and 4 threads, through the guarded step, for every integrator.
TEST(Determinism, SameStateForOneTwoAndFourThreads) {
  for (const Integrator integrator :
       {Integrator::ExplicitEuler, Integrator::SymplecticEuler, Integrator::SemiImplicit001,
        Integrator::Xpbd, Integrator::ImplicitEuler, Integrator::ImplicitPredictor}) {
    uint64_t hashes[3] = {};
    int k = 0;
    for (const int threads : {1, 2, 4}) {
      Body b = deform_test::make_capsule(2, 20.0, 0.02);
      ASSERT_GT(b.blocks.count(), 4u);
      ASSERT_GT(b.particles.slots.size(), deform::kParticleGrain);  // two chunks or more
      b.dynamics.integrator = integrator;
      b.dynamics.mass_scale = 1.0e4f;
      b.dynamics.damping_per_s = 50.0f;
      b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
      b.loads.push_back({deform_test::centre_particle(b), 0.0f, 0.0f, -0.05f});
      deform::DeformState st;
      tbb::task_arena arena(threads);
      arena.execute([&] {
        for (int s = 0; s < 8; ++s) {
          deform::Membrane m = b.membrane();
          deform::step(m, 2e-5, st);
        }
      });
      ASSERT_TRUE(deform_test::all_finite(b.particles));
      hashes[k++] = deform_test::hash_state(b.particles);
    }
    EXPECT_EQ(hashes[0], hashes[1]) << to_string(integrator);
    EXPECT_EQ(hashes[0], hashes[2]) << to_string(integrator);
  }
}

// With an active set only its particles move; the sleeping rest keeps every bit.
TEST(ActiveSet, OnlyActiveParticlesMove) {
  for (const Integrator integrator : {Integrator::ExplicitEuler, Integrator::SymplecticEuler,
                                      Integrator::SemiImplicit001, Integrator::Xpbd}) {
    Body b =
        deform_test::make_grid(15, 0.5, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
    b.dynamics.integrator = integrator;
    const uint32_t centre = deform_test::centre_particle(b);
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
      if (std::hypot(b.particles.x[i] - b.particles.x[centre],
                     b.particles.y[i] - b.particles.y[centre]) < 1.1)
        b.active.push_back(i);
    }
    for (uint32_t e = 0; e < b.springs.slots.size(); ++e) {
      const bool in_i = std::binary_search(b.active.begin(), b.active.end(), b.springs.i[e]);
      const bool in_j = std::binary_search(b.active.begin(), b.active.end(), b.springs.j[e]);
      if (in_i || in_j) b.active_springs.push_back(e);
    }
    b.loads.push_back({centre, 0.0f, 0.0f, -0.01f});
    const Particles before = b.particles;
    deform::DeformState st;
    for (int s = 0; s < 20; ++s) {
      deform::Membrane m = b.membrane();
      deform::step(m, 1e-5, st);
    }
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
      const bool active = std::binary_search(b.active.begin(), b.active.end(), i);
      if (!active) {
        EXPECT_EQ(b.particles.z[i], before.z[i]) << to_string(integrator) << " particle " << i;
      }
    }
    EXPECT_LT(b.particles.z[centre], before.z[centre]) << to_string(integrator);
  }
}

// Every integrator reaches the same static equilibrium under gravity and a point load, with mass
// scaling changing only inertia: the residual of the true forces (weight of the true mass, the
// load, the springs) vanishes at rest. Guards against an integrator that drops the loads or weighs
// with the scaled mass (the implicit ones once did both). XPBD is left out: with particles this
// light every constraint's α/dt² is tiny against 1/m, so each projection is nearly hard (the weak
// glue included) and a few iterations per step leave a residual of about a quarter of the load
// (measured 0.005 mN of 0.02; docs/dynamics.md).
TEST(Equilibrium, PointLoadAndTrueWeightReachedByEveryStableIntegrator) {
  for (const Integrator integrator :
       {Integrator::ImplicitEuler, Integrator::ImplicitPredictor, Integrator::SemiImplicit001}) {
    Body b = deform_test::make_grid(9, 0.5, 1e-6, {.sheet_modulus_mn_mm = 1.0, .prestretch = 0.05});
    b.dynamics.integrator = integrator;
    b.dynamics.mass_scale = 50.0f;
    b.dynamics.damping_per_s = 200.0f;
    b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
    const uint32_t centre = deform_test::centre_particle(b);
    b.loads.push_back({centre, 0.0f, 0.0f, -0.02f});
    deform::DeformState st;
    for (int s = 0; s < 3000; ++s) {
      deform::Membrane m = b.membrane();
      deform::step(m, 1e-3, st);
    }
    deform::Membrane m = b.membrane();
    b.dynamics.damping_per_s = 0.0f;  // the residual of the static forces only
    deform::compute_forces(m);
    double worst = 0.0;
    for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
      if (b.particles.kind[i] != ParticleKind::Free) continue;
      worst = std::max(worst, static_cast<double>(std::fabs(b.forces.fz[i])));
    }
    EXPECT_LT(worst, 1e-3 * 0.02) << to_string(integrator) << ": residual vs the 0.02 mN load";
    EXPECT_LT(b.particles.z[centre], -1e-3f)
        << to_string(integrator) << ": the load pushes the centre down";
  }
}

}  // namespace
}  // namespace phaco
