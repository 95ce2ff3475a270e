// Stability maps against theory: symplectic Euler's ω·dt < 2, explicit Euler's growth at every dt,
// the stable-everywhere methods, and the map's scaling dt_max ∝ √(m/k).
#include <gtest/gtest.h>

#include <cmath>

#include "systems/deform/stability.hpp"

namespace phaco {
namespace {

using deform::ProbeBody;
using deform::StabilityProbe;

TEST(Stability, SymplecticEulerOnOneSpringMassStopsAtOmegaDtTwo) {
  StabilityProbe probe{.body = ProbeBody::SpringMass, .steps = 400};
  for (const double k : {1.0, 100.0}) {
    for (const double m : {1e-6, 1e-3}) {
      const auto r = deform::largest_stable_dt(Integrator::SymplecticEuler, k, m, probe);
      ASSERT_FALSE(r.stable_everywhere);
      ASSERT_FALSE(r.unstable_everywhere);
      // Beyond 2 the amplification is real and > 1; below, the oscillation is bounded.
      EXPECT_GT(r.omega_dt(), 1.98) << "k " << k << " m " << m;
      EXPECT_LT(r.omega_dt(), 2.0 + 1e-3) << "k " << k << " m " << m;
    }
  }
}

TEST(Stability, ExplicitEulerUndampedHasNoStableStepOnlyAFiniteTrialOne) {
  // Between the trial's halves the energy grows by (1 + ω²dt²)^(N/2); the probe's bound 2 is met
  // only below ω·dt = √(2·ln 2 / N), a limit that shrinks as the trial grows: unstable at every dt.
  double previous = 1e9;
  for (const uint32_t steps : {100u, 400u, 1600u}) {
    StabilityProbe probe{.body = ProbeBody::SpringMass, .steps = steps};
    const auto r = deform::largest_stable_dt(Integrator::ExplicitEuler, 1.0, 1e-3, probe);
    const double theory = std::sqrt(2.0 * std::log(2.0) / steps);
    EXPECT_NEAR(r.omega_dt() / theory, 1.0, 0.05) << steps;
    EXPECT_LT(r.omega_dt(), previous);
    previous = r.omega_dt();
  }
  // Damping c makes it stable for c > ω²·dt (for small c·dt): roughly dt_max ≈ c/ω².
  StabilityProbe damped{.body = ProbeBody::SpringMass, .damping_per_s = 20.0, .steps = 3000};
  const auto r = deform::largest_stable_dt(Integrator::ExplicitEuler, 1.0, 1e-3, damped);
  EXPECT_NEAR(r.dt_max_s / (20.0 / 1000.0), 1.0, 0.15);
}

TEST(Stability, ImplicitFamilyAndXpbdAreStableOverTheWholeRange) {
  StabilityProbe probe{.body = ProbeBody::Patch, .patch_side = 5, .steps = 60, .max_omega_dt = 1e3};
  for (const Integrator integrator : {Integrator::SemiImplicit001, Integrator::Xpbd,
                                      Integrator::ImplicitEuler, Integrator::ImplicitPredictor}) {
    const auto r = deform::largest_stable_dt(integrator, 10.0, 1e-6, probe);
    EXPECT_TRUE(r.stable_everywhere) << to_string(integrator) << " dt_max·ω " << r.omega_dt();
  }
}

// On the patch the highest mode is faster than one spring's ω (ω_max² ≤ 2·Σk/m = 12·k/m at an
// interior node of valence 6): symplectic Euler's limit in units of 1/ω falls to 2/√12 … 2/√6 —
// and dt_max scales exactly as √(m/k) across the map.
TEST(Stability, PatchMapScalesAsSqrtMassOverStiffness) {
  StabilityProbe probe{.body = ProbeBody::Patch, .patch_side = 6, .steps = 300};
  const double ks[] = {1.0, 100.0}, ms[] = {1e-6, 1e-4};
  const auto map = deform::stability_map(Integrator::SymplecticEuler, ks, ms, probe);
  ASSERT_EQ(map.cells.size(), 4u);
  const double reference = map.cells[0].omega_dt();
  EXPECT_GT(reference, 2.0 / std::sqrt(12.0) * 0.95);
  EXPECT_LT(reference, 2.0 / std::sqrt(6.0) * 1.1);
  for (const auto& cell : map.cells) EXPECT_NEAR(cell.omega_dt() / reference, 1.0, 0.02);
  std::printf("[ figures  ] symplectic Euler on a 6×6 pinned patch: dt_max·√(k/m) = %.4f\n",
              reference);
}

}  // namespace
}  // namespace phaco
