// Real capsule tissue (E = 2 MPa, h = 0.013 mm, ρ = 1000 kg/m³) is stiff: the explicit limit is
// microseconds, the frame step is 1/120 s. What the guard does about it, and what mass scaling
// (the other way out for an explicit method) costs.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>

#include "tests/systems/deform/deform_fixtures.hpp"

namespace phaco {
namespace {

using deform_test::Body;

// Real capsule tissue (E = 2 MPa, h = 0.013 mm, ρ = 1000 kg/m³): the explicit limit is
// microseconds. Symplectic Euler at the frame step diverges at every substep count the guard may
// try; the guard falls back to implicit Euler and the capsule stays finite and slow.
TEST(RealTissue, SymplecticAtTheFrameStepFallsBackToImplicit) {
  Body level3 = deform_test::make_capsule(3);
  const double k_over_m = springs::max_stiffness_over_mass(level3.springs, level3.particles);
  const double dt_limit = 2.0 / std::sqrt(2.0 * k_over_m);  // symplectic, Gershgorin bound on ω_max
  std::printf(
      "[ figures  ] capsule level 3: %u particles, max Σk/m = %.3g 1/s², symplectic limit ≈ %.3g "
      "s\n",
      level3.particles.slots.size(), k_over_m, dt_limit);
  EXPECT_LT(dt_limit, 1e-5);                // microseconds: the frame step is ~10³ times beyond it
  EXPECT_GT(1.0 / 120.0 / dt_limit, 64.0);  // beyond what 64 substeps can rescue

  Body& b = level3;
  b.dynamics.integrator = Integrator::SymplecticEuler;
  b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
  b.loads.push_back({deform_test::centre_particle(b), 0.0f, 0.0f, -1.0f});
  deform::DeformState st;
  for (int s = 0; s < 2; ++s) {
    deform::Membrane m = b.membrane();
    const auto report = deform::step(m, 1.0 / 120.0, st);
    ASSERT_TRUE(deform_test::all_finite(b.particles));
    if (s == 0) {
      EXPECT_TRUE(report.diverged);
      EXPECT_TRUE(report.fell_back);
      // 1, 2, 4, ... 64 substeps of symplectic Euler (7 attempts), then the fallback, which may
      // substep too: the 1 mN load on one real-mass node is fast enough to trip the speed bound.
      EXPECT_GE(report.attempts, 8u);
      EXPECT_EQ(report.integrator, Integrator::ImplicitEuler);
      EXPECT_FALSE(report.held);
    } else {
      EXPECT_FALSE(report.diverged);  // the recovery sticks
    }
  }
  EXPECT_EQ(st.status.in_use, Integrator::ImplicitEuler);
  EXPECT_EQ(st.status.fallbacks, 1u);
  EXPECT_LT(deform_test::max_speed(b.particles), b.dynamics.max_speed_mm_s);
}

// A flat pinned patch of capsule material, pre-tensioned (2 %), under a 0.01 mN point load:
// the static sag is the same with the true mass at a microsecond step and with the mass scaled by
// the factor that makes symplectic Euler stable at the frame step (mass scaling changes inertia
// only, forces.hpp). What scaling costs is time: the scaled body reaches that sag √s times slower.
TEST(RealTissue, MassScalingKeepsTheStaticSagAndSlowsTheResponse) {
  constexpr double kSpacing = 0.17;  // mm, about the level-0 capsule's edge
  constexpr double kNodeMass =
      deform_test::kCapsuleDensityKgMm3 * deform_test::kCapsuleThicknessMm * kSpacing * kSpacing;
  constexpr double kLoad = 0.01, kFrame = 1.0 / 120.0;
  const auto make = [&] {
    Body b = deform_test::make_grid(21, kSpacing, kNodeMass,
                                    {.sheet_modulus_mn_mm = 2000.0 * 0.013, .prestretch = 0.02});
    b.dynamics.integrator = Integrator::SymplecticEuler;
    b.dynamics.gravity_mm_s2 = {0.0f, 0.0f, -9810.0f};
    b.loads.push_back({deform_test::centre_particle(b), 0.0f, 0.0f, static_cast<float>(-kLoad)});
    return b;
  };
  // Sag of the centre after `duration`, and after `probe_time`.
  const auto run = [&](double scale, double dt, double damping, double duration, double probe_time,
                       double* sag_at_probe) {
    Body b = make();
    b.dynamics.mass_scale = static_cast<float>(scale);
    b.dynamics.damping_per_s = static_cast<float>(damping);
    const uint32_t centre = deform_test::centre_particle(b);
    const float z0 = b.particles.z[centre];
    deform::DeformState st;
    const int steps = static_cast<int>(std::ceil(duration / dt));
    for (int s = 0; s < steps; ++s) {
      deform::Membrane m = b.membrane();
      deform::step(m, dt, st);
      if ((s + 1) * dt <= probe_time) *sag_at_probe = z0 - b.particles.z[centre];
    }
    EXPECT_EQ(st.status.divergences, 0u) << "scale " << scale;
    return double{z0 - b.particles.z[centre]};
  };
  const Body probe = make();
  const double omega_max =
      std::sqrt(2.0 * springs::max_stiffness_over_mass(probe.springs, probe.particles));
  // True mass: ω_max·dt = 1, damped near critically for the slowest mode (~8·10³ rad/s).
  double true_at_frame = 0.0, true_at_01ms = 0.0;
  const double true_sag = run(1.0, 1.0 / omega_max, 16000.0, 1.5e-3, 1e-4, &true_at_01ms);
  true_at_frame = true_sag;  // settled well within one frame
  // Scaled: ω_max·dt = 1 at the frame step; damping scaled by 1/√s to keep the damping ratio.
  const double scale = std::pow(omega_max * kFrame, 2);
  double scaled_at_frame = 0.0, scaled_at_10 = 0.0;
  run(scale, kFrame, 16000.0 / std::sqrt(scale), 10 * kFrame, kFrame, &scaled_at_frame);
  const double scaled_sag =
      run(scale, kFrame, 16000.0 / std::sqrt(scale), 10.0, 10 * kFrame, &scaled_at_10);
  std::printf(
      "[ figures  ] capsule patch: ω_max = %.3g rad/s, mass scale for the frame step s = %.3g (√s "
      "= %.0f)\n"
      "[ figures  ] static sag: true mass %.6g mm, scaled %.6g mm (rel. difference %.2g)\n"
      "[ figures  ] true mass reaches %.0f %% of it in 0.1 ms; scaled: %.2f %% after one frame, "
      "%.0f %% after 10\n",
      omega_max, scale, std::sqrt(scale), true_sag, scaled_sag, scaled_sag / true_sag - 1.0,
      100 * true_at_01ms / true_sag, 100 * scaled_at_frame / true_sag,
      100 * scaled_at_10 / true_sag);
  EXPECT_GT(scale, 1e6);
  EXPECT_NEAR(scaled_sag / true_sag, 1.0, 2e-3);  // statics kept
  EXPECT_NEAR(true_at_frame / true_sag, 1.0, 1e-6);
  EXPECT_GT(true_at_01ms / true_sag, 0.5);      // the real capsule responds in ~0.1 ms
  EXPECT_LT(scaled_at_frame / true_sag, 0.05);  // the scaled one has hardly moved a frame later
  EXPECT_LT(scaled_at_10 / true_sag, 0.5);
}

}  // namespace
}  // namespace phaco
