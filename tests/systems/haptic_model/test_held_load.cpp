// A fragment held at the tip (systems/haptic_model/held_load, components/held_fragment.hpp):
// a synthetic held fragment's load against its references — the weight at rest, weight minus drag
// at constant speed, the inertia m·a while accelerating, the hold limit, no jolt when it is taken
// or dropped, finite at any mass.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "systems/haptic_model/haptic_model.hpp"

namespace phaco::haptic_model {
namespace {

// A quadrant-sized fragment in a viscous OVD (components/held_fragment.hpp's orders of magnitude,
// the mass and drag scaled up so that inertia and drag are well above the solver's tolerance).
HeldFragment quadrant() {
  HeldFragment h;
  h.held = true;
  h.fragment = 3;
  h.mass_kg = 4e-3f;
  h.drag_mn_s_per_mm = 0.4f;
  h.weight_mn = {0, 0, -2.0f};
  h.hold_limit_mn = 0;
  return h;
}

std::unique_ptr<HapticTool> holding(const HeldFragment& h) {
  auto t = std::make_unique<HapticTool>();
  t->present = true;
  t->tip_radius_mm = 0.45f;
  t->held = h;
  t->tip_mm = {1, 2, 3};  // where the tests' device starts
  return t;
}

std::unique_ptr<HapticToolState> adopted(const HapticTool& t, const HapticSettings& s) {
  auto st = std::make_unique<HapticToolState>();
  adopt_model(t, *st, s);
  return st;
}

TEST(HeldLoad, AtRestTheHandCarriesTheWeight) {
  HapticSettings s;
  auto t = holding(quadrant());
  auto st = adopted(*t, s);
  const HapticForce first = haptic_tick(*t, Vec3(1, 2, 3), Vec3::Zero(), s, *st);
  EXPECT_NEAR(first.force_mn.z(), -2.0, 1e-6) << "taken with its weight already hanging: no jolt";
  HapticForce f;
  for (int k = 0; k < 500; ++k) f = haptic_tick(*t, Vec3(1, 2, 3), Vec3::Zero(), s, *st);
  EXPECT_NEAR(f.force_mn.z(), -2.0, 1e-9);
  EXPECT_NEAR(f.force_mn.x(), 0.0, 1e-9);
  EXPECT_TRUE(f.active & kTermHeld);
  EXPECT_NEAR(f.held_load_mn.z(), -2.0, 1e-9);
}

TEST(HeldLoad, AtConstantSpeedTheDragAddsToTheWeight) {
  HapticSettings s;
  auto t = holding(quadrant());
  auto st = adopted(*t, s);
  const Vec3 v(20, 0, 10);  // mm/s
  HapticForce f;
  for (int k = 0; k < 2000; ++k) f = haptic_tick(*t, Vec3(1, 2, 3) + v * (k * s.dt_s), v, s, *st);
  const Vec3 expected = Vec3(0, 0, -2.0) - 0.4 * v;
  EXPECT_LT((f.force_mn - expected).norm(), 1e-3 * expected.norm()) << f.force_mn.transpose();
}

TEST(HeldLoad, WhileAcceleratingTheInertiaIsFelt) {
  HapticSettings s;
  HeldFragment h = quadrant();
  h.drag_mn_s_per_mm = 0;
  auto t = holding(h);
  auto st = adopted(*t, s);
  const double a = 500;  // mm/s² along x
  HapticForce f;
  for (int k = 0; k < 400; ++k) {
    const double time = k * s.dt_s;
    f = haptic_tick(*t, Vec3(1 + 0.5 * a * time * time, 2, 3), Vec3(a * time, 0, 0), s, *st);
  }
  // m·a = 4e-3 kg · 500 mm/s² = 2 mN against the motion (kg·mm/s² = mN).
  EXPECT_NEAR(f.force_mn.x(), -4e-3 * a, 0.02 * 4e-3 * a);
  EXPECT_NEAR(f.force_mn.z(), -2.0, 0.02);
}

TEST(HeldLoad, TheOcclusionHoldsNoMoreThanItsLimitAndDroppingIsSmooth) {
  HapticSettings s;
  HeldFragment h = quadrant();
  h.hold_limit_mn = 5.0f;
  auto t = holding(h);
  auto st = adopted(*t, s);
  const Vec3 v(40, 0, 0);  // drag 16 mN beyond the 5 mN hold
  HapticForce f;
  for (int k = 0; k < 1000; ++k) {
    f = haptic_tick(*t, Vec3(1, 2, 3) + v * (k * s.dt_s), v, s, *st);
    ASSERT_LE(f.held_load_mn.norm(), 5.0 * (1 + 1e-9));
  }
  EXPECT_NEAR(f.force_mn.norm(), 5.0, 1e-6);
  // The simulation lets go: the next model has nothing held; the load fades over the crossfade.
  auto released = holding(h);
  released->held.held = false;
  adopt_model(*released, *st, s);
  Vec3 last = f.force_mn;
  double jump = 0;
  for (int k = 1000; k < 1100; ++k) {
    f = haptic_tick(*released, Vec3(1, 2, 3) + v * (k * s.dt_s), v, s, *st);
    jump = std::max(jump, (f.force_mn - last).norm());
    last = f.force_mn;
  }
  EXPECT_EQ(f.force_mn.norm(), 0.0);
  EXPECT_LE(jump, s.blend_max_step_mn + 1e-9) << "faded out at the crossfade's rate, not dropped";
}

TEST(HeldLoad, FiniteAtAnyMass) {
  HapticSettings s;
  for (float m : {0.0f, 1e-9f, 4e-5f, 10.0f}) {
    HeldFragment h = quadrant();
    h.mass_kg = m;
    auto t = holding(h);
    auto st = adopted(*t, s);
    HapticForce f;
    for (int k = 0; k < 300; ++k) {
      const double time = k * s.dt_s;
      f = haptic_tick(*t, Vec3(1 + std::sin(40 * time), 2, 3), Vec3(40 * std::cos(40 * time), 0, 0),
                      s, *st);
      ASSERT_TRUE(std::isfinite(f.force_mn.norm())) << m;
    }
    EXPECT_LT(f.force_mn.norm(), 1e3) << m;
  }
}

}  // namespace
}  // namespace phaco::haptic_model
