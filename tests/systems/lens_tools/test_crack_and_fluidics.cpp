// The chopper's crack (crack.hpp) and the probe's fluidics (fluidics.hpp) against their equations:
// the push is k·(growth of the tips' separation) while both tips touch one fragment across an
// empty gap, and cracks at strength × hardness; the links across the plane are exactly those whose
// cells lie on opposite sides; the vacuum follows dP/dt = (P* − P)/τ with τ = C·P_limit/Q; the
// pull is P·A; the port's cover is the covered cells' volume over the port sphere's.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>

#include "engine/core/rng.hpp"
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

// The rule as written in crack.hpp, walked over every cell: the nearest alive cell to each tip,
// then per candidate fragment the other tip's nearest cell of it and its nearest cell to the
// midpoint (lowest id among equals). push_apart looks only near the tips; it must decide alike.
CrackPush push_apart_over_every_cell(const CrackCells& c, const Vec3& probe, const Vec3& chopper,
                                     const CrackSettings& s, CrackState& state) {
  constexpr uint32_t kNo = 0xffffffffu;
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const Vec3f p = probe.cast<float>(), q = chopper.cast<float>(), m = 0.5f * (p + q);
  auto d2 = [&](uint32_t i, const Vec3f& t) {
    return (Vec3f(c.x[i], c.y[i], c.z[i]) - t).squaredNorm();
  };
  auto nearest = [&](const Vec3f& t, uint32_t label, float& best) {
    uint32_t at = kNo;
    best = kInf;
    for (uint32_t i = 0; i < c.x.size(); ++i)
      if (c.alive[i] && (label == kNo || c.label[i] == label) && d2(i, t) < best)
        best = d2(i, t), at = i;
    return at;
  };
  CrackPush out;
  float dp = kInf, dq = kInf;
  const uint32_t np = nearest(p, kNo, dp), nq = nearest(q, kNo, dq);
  const double separation = (probe - chopper).norm();
  if (np == kNo || nq == kNo || separation <= 0) return state = {}, out;
  const uint32_t fp = c.label[np], fq = c.label[nq];
  float q_fp = kInf, p_fq = kInf, gap_fp = kInf, gap_fq = kInf;
  const uint32_t q_on_fp = nearest(q, fp, q_fp), p_on_fq = nearest(p, fq, p_fq);
  nearest(m, fp, gap_fp), nearest(m, fq, gap_fq);
  const float contact2 = float(s.contact_radius_mm * s.contact_radius_mm);
  const float gap2 = float(s.gap_radius_mm * s.gap_radius_mm);
  const bool on_fp = dp <= contact2 && q_fp <= contact2 && gap_fp >= gap2;
  const bool on_fq = dq <= contact2 && p_fq <= contact2 && gap_fq >= gap2;
  if (!on_fp && !on_fq) return state = {}, out;
  const uint32_t a = on_fp ? np : p_on_fq, b = on_fp ? q_on_fp : nq;
  if (!state.engaged || state.fragment != c.label[a]) state = {true, separation, c.label[a]};
  state.rest_separation_mm = std::min(state.rest_separation_mm, separation);
  out.engaged = true;
  out.fragment = c.label[a];
  out.force_mn = s.stiffness_mn_mm * (separation - state.rest_separation_mm);
  out.crack_force_mn = s.strength_mn * 0.5 * (double(c.hardness[a]) + double(c.hardness[b]));
  out.crack = out.force_mn >= out.crack_force_mn;
  out.mid = m.cast<double>();
  out.normal = (probe - chopper) / separation;
  if (out.crack) state = {};
  return out;
}

TEST(Crack, LooksOnlyNearTheTipsYetDecidesAsAWalkOverEveryCell) {
  // The slabs cut into four fragments with some cells gone and crumbs of a fifth in the trench;
  // tip pairs across the trench, inside a slab, astride two fragments and far away, each pair
  // spreading over a few frames. Every output and the state must match the walk over every cell.
  Slabs s;
  const CounterRng rng(19, 3);
  for (size_t i = 0; i < s.x.size(); ++i) {
    s.label[i] = (s.y[i] > 0.3f ? 1u : 0u) + (s.z[i] > 0.5f ? 2u : 0u);
    s.alive[i] = rng.uniform(0, uint32_t(i)) > 0.1f;
    s.hardness[i] = 0.3f + 0.4f * rng.uniform(1, uint32_t(i));
  }
  for (const float py : {-0.4f, 0.2f, 0.6f})
    s.x.push_back(0.1f), s.y.push_back(py), s.z.push_back(0), s.hardness.push_back(0.5f),
        s.alive.push_back(1), s.label.push_back(4);
  CrackSettings cs;
  cs.strength_mn = 8;  // cracks within the spreads below
  CrackState fast, walk;
  int engaged = 0, cracked = 0, disengaged = 0;
  for (uint32_t pair = 0; pair < 400; ++pair) {
    auto u = [&](uint32_t k) { return double(rng.uniform(2 + pair, k)); };
    const Vec3 centre(6 * u(0) - 3, 2.4 * u(1) - 1.2, 2.4 * u(2) - 1.2);
    const double half = 0.3 + 0.5 * u(3);
    Vec3 axis(1, 0.3 * (u(4) - 0.5), 0.3 * (u(5) - 0.5));
    axis.normalize();
    if (pair % 3 == 0) axis = Vec3(u(6) - 0.5, u(7) - 0.5, u(8) - 0.5).normalized();
    const Vec3 at = pair % 2 ? Vec3(0, centre.y(), centre.z()) : centre;
    for (int frame = 0; frame < 6; ++frame) {
      const double spread = half + 0.05 * frame;
      const Vec3 probe = at + spread * axis, chopper = at - spread * axis;
      const CrackPush a = push_apart(s.view(), probe, chopper, cs, fast);
      const CrackPush b = push_apart_over_every_cell(s.view(), probe, chopper, cs, walk);
      ASSERT_EQ(a.engaged, b.engaged) << pair << " " << frame;
      ASSERT_EQ(a.crack, b.crack) << pair << " " << frame;
      ASSERT_EQ(a.fragment, b.fragment) << pair << " " << frame;
      ASSERT_EQ(a.force_mn, b.force_mn) << pair << " " << frame;
      ASSERT_EQ(a.crack_force_mn, b.crack_force_mn) << pair << " " << frame;
      if (a.engaged) {
        ASSERT_TRUE(a.mid == b.mid);
        ASSERT_TRUE(a.normal == b.normal);
      }
      ASSERT_EQ(fast.engaged, walk.engaged);
      ASSERT_EQ(fast.fragment, walk.fragment);
      ASSERT_EQ(fast.rest_separation_mm, walk.rest_separation_mm);
      engaged += a.engaged, cracked += a.crack, disengaged += !a.engaged;
    }
  }
  // The cases covered all three outcomes, often.
  EXPECT_GT(engaged, 100);
  EXPECT_GT(cracked, 20);
  EXPECT_GT(disengaged, 500);
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
