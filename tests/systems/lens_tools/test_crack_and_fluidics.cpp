// The chopper's crack (crack.hpp) and the probe's fluidics (fluidics.hpp) against their equations:
// the push is k·(growth of the tips' separation) while both tips touch one fragment across an
// empty gap, and cracks at strength × hardness; the links across the plane are exactly those whose
// cells lie on opposite sides; the vacuum follows dP/dt = (P* − P)/τ with τ = C·P_limit/Q; the
// pull is P·A; the port's cover is the covered cells' volume over the port sphere's.
#include <gtest/gtest.h>

#include <cmath>

#include "systems/lens_tools/crack.hpp"
#include "systems/lens_tools/fluidics.hpp"

namespace phaco::lens_tools {
namespace {

// Two slabs of cells (x in [-3, -0.7] and [0.7, 3]) with a 1.4 mm trench between them, one
// fragment (label 0), a cell every 0.2 mm.
struct Slabs {
  std::vector<float> x, y, z, hardness;
  std::vector<uint8_t> alive;
  std::vector<uint32_t> label;
  Slabs() {
    for (float px = -3.0f; px <= 3.0f + 1e-4f; px += 0.2f) {
      if (std::abs(px) < 0.69f) continue;
      for (float py = -1.0f; py <= 1.0f + 1e-4f; py += 0.2f)
        for (float pz = -1.0f; pz <= 1.0f + 1e-4f; pz += 0.2f) {
          x.push_back(px), y.push_back(py), z.push_back(pz);
          hardness.push_back(0.5f), alive.push_back(1), label.push_back(0);
        }
    }
  }
  CrackCells view() const { return {x, y, z, alive, hardness, label}; }
};

TEST(Crack, PushIsStiffnessTimesSpreadAndCracksAtStrengthTimesHardness) {
  const Slabs s;
  CrackSettings cs;  // k = 100 mN/mm, strength 40 mN: cracks at 20 mN for hardness 0.5
  CrackState state;
  double spread = 0;
  bool cracked = false;
  for (int k = 0; k <= 30 && !cracked; ++k) {
    spread = 0.01 * k;
    const Vec3 probe(0.4 + spread / 2, 0, 0), chopper(-0.4 - spread / 2, 0, 0);
    const CrackPush p = push_apart(s.view(), probe, chopper, cs, state);
    ASSERT_TRUE(p.engaged) << k;
    EXPECT_NEAR(p.force_mn, cs.stiffness_mn_mm * spread, 1e-9);
    EXPECT_DOUBLE_EQ(p.crack_force_mn, cs.strength_mn * 0.5);
    cracked = p.crack;
    if (cracked) {
      EXPECT_NEAR(p.normal.x(), 1.0, 1e-12);
      EXPECT_NEAR(p.mid.x(), 0.0, 1e-6);
    }
  }
  EXPECT_TRUE(cracked);
  EXPECT_NEAR(spread, 0.2, 0.0101) << "20 mN at 100 mN/mm";
}

TEST(Crack, NoPushWithoutATrenchBetweenTheTipsOrWithTwoFragments) {
  Slabs s;
  CrackState state;
  // Both tips inside one slab: the midpoint is in material, not in a trench.
  EXPECT_FALSE(push_apart(s.view(), Vec3(1.6, 0, 0), Vec3(1.0, 0, 0), {}, state).engaged);
  // Across the trench but the walls are different fragments.
  for (size_t i = 0; i < s.x.size(); ++i) s.label[i] = s.x[i] > 0 ? 1 : 0;
  EXPECT_FALSE(push_apart(s.view(), Vec3(0.4, 0, 0), Vec3(-0.4, 0, 0), {}, state).engaged);
  // Far from everything.
  EXPECT_FALSE(push_apart(s.view(), Vec3(0.4, 5, 0), Vec3(-0.4, 5, 0), {}, state).engaged);
}

TEST(Crack, APieceOfAnotherFragmentLyingInTheTrenchDoesNotBridgeIt) {
  // A crumb of another fragment (label 1) at the trench's centre, next to the tips' midpoint and
  // nearer the chopper than its own wall: the walls are still one fragment with none of its cells
  // between them, so the push engages and cracks as in an empty trench. (In the nucleus drill a
  // quadrant that slid into the other half's trench after the second crack kept the third from
  // engaging at level 3, where the pieces sink further.)
  Slabs s;
  for (const float pz : {-0.2f, 0.0f, 0.2f})
    s.x.push_back(-0.1f), s.y.push_back(0), s.z.push_back(pz), s.hardness.push_back(0.5f),
        s.alive.push_back(1), s.label.push_back(1);
  CrackState state;
  bool cracked = false;
  for (int k = 0; k <= 30 && !cracked; ++k) {
    const double spread = 0.01 * k;
    const CrackPush p = push_apart(s.view(), Vec3(0.45 + spread / 2, 0, 0),
                                   Vec3(-0.45 - spread / 2, 0, 0), {}, state);
    ASSERT_TRUE(p.engaged) << k;
    EXPECT_EQ(p.fragment, 0u);
    cracked = p.crack;
  }
  EXPECT_TRUE(cracked);
  // A cell of the walls' own fragment at the midpoint is material, not a trench.
  s.label.back() = 0;
  state = {};
  EXPECT_FALSE(push_apart(s.view(), Vec3(0.45, 0, 0), Vec3(-0.45, 0, 0), {}, state).engaged);
}

TEST(Crack, LinksAcrossThePlaneAreThoseJoiningItsTwoSides) {
  // Five cells in a row along x, each linked to the next (face 0 forward, face 1 back).
  const std::vector<float> x{0, 1, 2, 3, 4}, y(5, 0.0f), z(5, 0.0f), h(5, 0.5f);
  const std::vector<uint8_t> alive(5, 1);
  const std::vector<uint32_t> label(5, 0);
  std::vector<std::array<uint32_t, 4>> nb(5, {0xffffffffu, 0xffffffffu, 0xffffffffu, 0xffffffffu});
  for (uint32_t i = 0; i + 1 < 5; ++i) nb[i][0] = i + 1, nb[i + 1][1] = i;
  std::vector<std::pair<uint32_t, uint32_t>> out;
  links_across({x, y, z, alive, h, label}, nb, 0, Vec3(2.5, 0, 0), Vec3::UnitX(), out);
  ASSERT_EQ(out.size(), 1u);
  EXPECT_EQ(out[0], (std::pair<uint32_t, uint32_t>{2, 0}));
  links_across({x, y, z, alive, h, label}, nb, 1, Vec3(2.5, 0, 0), Vec3::UnitX(), out);
  EXPECT_TRUE(out.empty()) << "another fragment's links";
}

TEST(Fluidics, VacuumRisesWithTheLinesTimeConstantTowardItsTarget) {
  FluidicsSettings s;  // 350 mmHg, 30 mL/min, C = 1e-3 mL/mmHg
  const double tau = vacuum_rise_time_s(s);
  EXPECT_NEAR(tau, 1e-3 * 350 / 0.5, 1e-12);
  double p = 0;
  const double dt = tau / 100;
  for (int k = 0; k < 100; ++k) p = step_vacuum(p, true, true, s, dt);
  EXPECT_NEAR(p, 350 * (1 - std::exp(-1.0)), 1e-9) << "one time constant occluded";
  for (int k = 0; k < 2000; ++k) p = step_vacuum(p, true, false, s, dt);
  EXPECT_NEAR(p, s.open_resistance_mmhg_per_ml_min * s.flow_ml_min, 1e-6) << "open tip: R·Q";
  for (int k = 0; k < 2000; ++k) p = step_vacuum(p, false, false, s, dt);
  EXPECT_NEAR(p, 0, 1e-6) << "pedal below 2 vents";
  EXPECT_NEAR(holding_force_mn(350, s), 350 * 0.133322 * M_PI * 0.45 * 0.45, 1e-9);
}

TEST(Fluidics, PortCoverIsTheCoveredVolumeOverThePortSphere) {
  LensCells c;
  c.resize(4);
  const std::vector<float> volume{0.05f, 0.05f, 0.05f, 0.05f};
  std::vector<uint32_t> label{0, 0, 1, 0};
  c.x = {0.1f, -0.1f, 0.0f, 2.0f};  // cells 0..2 in the port sphere, cell 3 far
  FluidicsSettings s;
  std::vector<double> scratch;
  const PortCover p = port_cover(cell_spans(c), volume, label, 2, Vec3::Zero(), s, scratch);
  const double sphere = 4.0 / 3.0 * M_PI * std::pow(s.port_radius_mm, 3);
  EXPECT_EQ(p.fragment, 0u);
  EXPECT_NEAR(p.fraction, 0.1 / sphere, 1e-6);
  EXPECT_EQ(p.occluded, 0.1 / sphere >= s.occlusion_fraction);
}

}  // namespace
}  // namespace phaco::lens_tools
