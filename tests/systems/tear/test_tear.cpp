// The tear rules (seed 000 flap force, seed 001 most stressed spring) and seed 004's run-out check.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <stdexcept>
#include <vector>

#include "systems/tear/tear.hpp"
#include "tests/support/grid_mesh.hpp"
#include "tests/systems/cut/cut_sheet.hpp"

namespace phaco::tear {
namespace {

const Vec3 kUp(0, 0, 1);

TEST(FlapForceStep, NeedsTheThresholdAndCombinesForceAndCutDirection) {
  TearSettings s;
  s.threshold_mn = 10.0;
  s.a_mm_per_mn = 0.001;
  s.b_mm = 0.02;
  s.max_step_mm = 1.0;
  const Vec3 tip(2, 0, 0), c_hat(0, 1, 0);
  EXPECT_EQ(flap_force_step(tip, kUp, c_hat, Vec3(9.9, 0, 0), s), Vec3::Zero())
      << "below the threshold";
  // The normal part of the force does not count toward the threshold.
  EXPECT_EQ(flap_force_step(tip, kUp, c_hat, Vec3(6, 0, 50), s), Vec3::Zero());
  const Vec3 step = flap_force_step(tip, kUp, c_hat, Vec3(30, 0, 5), s);
  EXPECT_NEAR((step - Vec3(0.03, 0.02, 0.0)).norm(), 0.0, 1e-12) << "c_{t+1} - c_t = a f + b ĉ";
  s.max_step_mm = 0.01;
  EXPECT_NEAR(flap_force_step(tip, kUp, c_hat, Vec3(30, 0, 5), s).norm(), 0.01, 1e-12) << "capped";
  s.max_step_mm = 1.0;
  s.outward_bias = 1.0;  // anterior bowing pushes the step outward (+x here)
  EXPECT_GT(flap_force_step(tip, kUp, c_hat, Vec3(0, 30, 0), s).x(), 0.0);
}

TEST(Runout, WarnsOnOutwardTurnsAndNearTheSafeEdge) {
  TearSettings s;
  s.safe_radius_mm = 3.5;
  s.warn_angle_deg = 30.0;
  s.warn_lookahead_mm = 0.75;
  const Vec3 tip(2.6, 0, 1);
  EXPECT_FALSE(check_runout(tip, Vec3(0, 1, 0), s).warn) << "tangential, well inside";
  EXPECT_NEAR(check_runout(tip, Vec3(0, 1, 0), s).outward_angle_deg, 0.0, 1e-9);
  const RunoutCheck out = check_runout(tip, Vec3(1, 1, 0), s);
  EXPECT_NEAR(out.outward_angle_deg, 45.0, 1e-9);
  EXPECT_TRUE(out.warn);
  EXPECT_FALSE(check_runout(tip, Vec3(-1, 1, 0), s).warn) << "turning inward";
  EXPECT_TRUE(check_runout(Vec3(3.45, 0, 0), Vec3(0, 1, 0), s).warn)
      << "tangential but about to leave";
  EXPECT_NEAR(check_runout(Vec3(3.0, 0, 0), Vec3(1, 0, 0), s).distance_to_safe_edge_mm, 0.5, 1e-12);
}

// A 7 × 7 unit grid cut from (1.5, 3) to the vertex (3, 3), then two of the tip's neighbours
// pulled away so that one spring at the tip is over-extended and another only stretched.
TEST(MostStressedSpring, BreaksTheOverExtendedSpringWithTheLargestForce) {
  cut::test::CutSheet s = cut::test::cut_sheet(phaco::test::grid_mesh(7, 0.0), 0.0);
  cut::CutMesh m = s.mesh();
  cut::CutPath path;
  cut::EditLog log;
  cut::CutSettings cs;
  cut::cut_towards(m, path, Vec3(1.5, 3.0, 0), cs, log);
  cut::cut_towards(m, path, Vec3(3.0, 3.0, 0), cs, log);  // tip at vertex (3, 3) = 24
  ASSERT_EQ(path.tip, 24u);
  TearSettings t;
  t.rule = TearRule::MostStressedSpring;
  t.break_strain = 0.29;
  EXPECT_EQ(most_stressed_spring_end(m, path.tip, t), kInvalidIndex) << "nothing over-extended yet";
  // Pull (4, 3) = 25 away by 40 % of the edge and (3, 4) = 31 by 20 %: only the first breaks.
  s.particles.x[25] += 0.4f;
  s.particles.y[31] += 0.2f;
  EXPECT_EQ(most_stressed_spring_end(m, path.tip, t), 25u);
  TearState state;
  const TearStepReport r = tear_step(m, path, state, Vec3::Zero(), t, cs, log);
  EXPECT_TRUE(r.advanced);
  EXPECT_EQ(path.tip, 25u) << "the tear runs along the broken spring";
  EXPECT_EQ(r.segment.cut_case, cut::CutCase::SC3);
  EXPECT_EQ(most_stressed_spring_end(m, path.tip, t), kInvalidIndex);
  // The broken spring is gone from the joined edges: the lips of the cut hold two springs now.
  EXPECT_TRUE(cut::test::sound(s));
}

TEST(TearStep, WarnsOncePerOutwardExcursionAndRecordsTheTearOutOnce) {
  cut::test::CutSheet s = cut::test::cut_sheet(phaco::test::grid_mesh(12, 0.1), 0.0);
  cut::CutMesh m = s.mesh();
  cut::CutPath path;
  cut::EditLog log;
  cut::CutSettings cs;
  // Axis at the grid's corner (0, 0): the tear starts at radius ≈ 4 and heads outward.
  cut::cut_towards(m, path, Vec3(2.9, 2.0, 0), cs, log);
  cut::cut_towards(m, path, Vec3(3.0, 2.9, 0), cs, log);
  TearSettings t;
  t.safe_radius_mm = 5.0;
  t.threshold_mn = 1.0;
  t.a_mm_per_mn = 0.01;
  t.b_mm = 0.0;
  t.max_step_mm = 0.3;
  TearState state;
  for (int k = 0; k < 20 && !state.complete; ++k)
    tear_step(m, path, state, Vec3(30, 30, 0), t, cs, log);
  EXPECT_EQ(state.count(TearEvent::RunoutWarning), 1u);
  EXPECT_EQ(state.count(TearEvent::RadialTearout), 1u);
  ASSERT_FALSE(state.events.empty());
  EXPECT_EQ(state.events.front().kind, TearEvent::RunoutWarning);
  EXPECT_LT(state.events.front().radius_mm, t.safe_radius_mm);
  EXPECT_GT(state.max_radius_mm, t.safe_radius_mm);
  EXPECT_TRUE(cut::test::sound(s));
}

TEST(TearStep, RefusesToTearWithoutACutOrWithABadForce) {
  cut::test::CutSheet s = cut::test::cut_sheet(phaco::test::grid_mesh(5, 0.0));
  cut::CutMesh m = s.mesh();
  cut::CutPath path;
  cut::EditLog log;
  TearState state;
  EXPECT_THROW(tear_step(m, path, state, Vec3(20, 0, 0), {}, {}, log), std::invalid_argument);
  cut::cut_towards(m, path, Vec3(1.2, 1.3, 0), {}, log);
  cut::cut_towards(m, path, Vec3(2.3, 1.6, 0), {}, log);
  EXPECT_THROW(tear_step(m, path, state, Vec3(std::nan(""), 0, 0), {}, {}, log),
               std::invalid_argument);
}

// The tear as the force limit (issue 17 item 5). A flap modelled as a linear strip of stiffness k
// between the forceps and the tear's tip: the forceps move along +x by `pull_mm` a frame, the
// force is k·(u − a) (u the forceps' travel, a the tear's advance), and each frame
// tear_until_below runs the tear. Returns the force the forceps feel each frame once the tear has
// started (before that frame's tear), and the frame it started at.
struct Pulled {
  std::vector<double> force;  // per frame from the first tear on, mN
  double first_tear_force = 0;
  double advance_mm = 0;
};
Pulled pull_flap(double pull_mm, bool several_steps) {
  cut::test::CutSheet s = cut::test::cut_sheet(phaco::test::grid_mesh(20, 0.0), 0.0);
  cut::CutMesh m = s.mesh();
  cut::CutPath path;
  cut::EditLog log;
  cut::CutSettings cs;
  cut::cut_towards(m, path, Vec3(2.3, 9.4, 0), cs, log);
  cut::cut_towards(m, path, Vec3(4.0, 9.4, 0), cs, log);
  TearSettings t;
  t.threshold_mn = tear_resistance_mn(1500.0, 0.013);  // the standard eye's F_c ≈ 9.75 mN
  t.safe_radius_mm = 100.0;                            // no run-out on this sheet
  if (!several_steps) t.max_steps = 1;
  const double k = 10.0;  // mN/mm
  TearState state;
  Pulled out;
  double u = 0.0, a = 0.0;
  bool started = false;
  while (a < 10.0 && u < 40.0 && !state.complete) {
    u += pull_mm;
    const double f = k * std::max(0.0, u - a);
    if (started) out.force.push_back(f);
    const TearRunReport run = tear_until_below(m, path, state, Vec3(f, 0, 0), f / k, t, cs, log);
    if (run.steps > 0 && !started) started = true, out.first_tear_force = f;
    a += run.advance_mm;
  }
  out.advance_mm = a;
  EXPECT_TRUE(cut::test::sound(s));
  return out;
}

TEST(TearResistance, IsATrouserTearsGcTimesHOverTwo) {
  EXPECT_NEAR(tear_resistance_mn(1500.0, 0.013), 9.75, 1e-12);  // J/m² = mN/mm
  EXPECT_NEAR(tear_resistance_mn(3000.0, 0.013), 2 * tear_resistance_mn(1500.0, 0.013), 1e-12);
  EXPECT_THROW(tear_resistance_mn(0.0, 0.013), std::invalid_argument);
  EXPECT_THROW(tear_resistance_mn(1500.0, std::nan("")), std::invalid_argument);
}

TEST(TearUntilBelow, ASlowlyRisingPullTearsAtAPlateauEqualToTheResistance) {
  const double fc = tear_resistance_mn(1500.0, 0.013);
  const Pulled p = pull_flap(0.01, true);  // the force rises by 0.1 mN a frame
  EXPECT_GT(p.advance_mm, 9.0) << "the tear ran along the sheet";
  EXPECT_GE(p.first_tear_force, fc);
  EXPECT_LT(p.first_tear_force, fc + 0.11) << "the tear starts the frame the pull reaches F_c";
  ASSERT_GT(p.force.size(), 100u);
  double mean = 0, peak = 0;
  for (double f : p.force) mean += f, peak = std::max(peak, f);
  mean /= double(p.force.size());
  EXPECT_LE(peak, fc + 0.11) << "the force never ramps above the plateau";
  EXPECT_NEAR(mean, fc, 0.1 * fc) << "the plateau is the resistance";
}

TEST(TearUntilBelow, AFastPullStillPlateausBecauseTheTearRunsSeveralStepsAFrame) {
  const double fc = tear_resistance_mn(1500.0, 0.013);
  const Pulled fast = pull_flap(0.5, true);  // 5 mN a frame: more than one step's relief
  ASSERT_GT(fast.force.size(), 5u);
  for (double f : fast.force) EXPECT_LE(f, fc + 5.0 + 1e-9);
  // One step a frame (seed 000's rule alone) cannot keep up: the force ramps far above F_c.
  const Pulled single = pull_flap(0.5, false);
  double peak = 0;
  for (double f : single.force) peak = std::max(peak, f);
  EXPECT_GT(peak, 3 * fc);
}

// The tear's last step (tear.hpp, "the ligament to its own start"): a path cut round three sides of
// a rectangle on a 12 × 12 unit sheet and back down toward its first side, its tip `gap_mm` above
// that side's middle. The pull is under F_c, as when the disc is all but free (2–4 mN in the
// level-1 capsulorhexis that stalled 0.02–0.06 mm from its slit).
struct LoopedTear {
  cut::test::CutSheet sheet = cut::test::cut_sheet(phaco::test::grid_mesh(12, 0.0), 0.0);
  cut::CutMesh m = sheet.mesh();
  cut::CutPath path;
  cut::EditLog log;
  cut::CutSettings cs;
  TearSettings t;
  TearState state;
  explicit LoopedTear(double gap_mm) {
    for (const Vec3& p : {Vec3(2.3, 3.4, 0), Vec3(8.6, 3.4, 0), Vec3(8.6, 8.6, 0),
                          Vec3(5.3, 8.6, 0), Vec3(5.3, 3.4 + gap_mm, 0)})
      cut::cut_towards(m, path, p, cs, log), state.trail.push_back(p);
    state.trail.back() = tip();  // as tear_step records it: the tip where the cut put it
    t.threshold_mn = tear_resistance_mn(1500.0, 0.013);  // 9.75 mN
    t.safe_radius_mm = 100.0;
    t.ligament_strength_mn_per_mm = 700.0 * 0.013;  // σ_u·h of the standard eye, 9.1 mN/mm
  }
  Vec3 tip() const { return cut::particle_position(sheet.particles, path.tip); }
};

TEST(Ligament, OnlyThePartOfItsOwnCutATearHasComeRoundToCounts) {
  LoopedTear near(0.25);
  const Ligament l = own_ligament(near.state.trail, near.tip());
  ASSERT_TRUE(l.found);
  EXPECT_NEAR(l.width_mm, near.tip().y() - 3.4, 1e-9) << "to the first side, below the tip";
  EXPECT_NEAR((l.to - Vec3(near.tip().x(), 3.4, 0)).norm(), 0.0, 1e-9);
  // A straight cut and one turning by a right angle hold no ligament behind their tips.
  cut::test::CutSheet s = cut::test::cut_sheet(phaco::test::grid_mesh(12, 0.0), 0.0);
  cut::CutMesh m = s.mesh();
  cut::CutPath path;
  cut::EditLog log;
  std::vector<Vec3> trail;
  for (const Vec3& p : {Vec3(2.3, 3.4, 0), Vec3(8.6, 3.4, 0), Vec3(8.6, 8.6, 0)})
    cut::cut_towards(m, path, p, {}, log), trail.push_back(p);
  EXPECT_FALSE(own_ligament(trail, cut::particle_position(s.particles, path.tip)).found);
  trail.pop_back();
  EXPECT_FALSE(own_ligament(trail, Vec3(8.6, 3.4, 0)).found) << "straight";
}

TEST(Ligament, ASliverShortOfItsOwnStartBreaksUnderAPullUnderTheResistance) {
  LoopedTear loop(0.25);
  const double gap = loop.tip().y() - 3.4;
  ASSERT_GT(gap, 0.1);
  ASSERT_LT(gap, 0.25);
  const Vec3 pull(0.0, 3.0, 0.0);  // 3 mN > σ_u·h·gap ≈ 1.8 mN, < F_c
  TearSettings off = loop.t;
  off.ligament_strength_mn_per_mm = 0.0;
  TearStepReport r = tear_step(loop.m, loop.path, loop.state, pull, off, loop.cs, loop.log);
  EXPECT_FALSE(r.advanced) << "without the rule the tear waits under F_c a sliver short";
  EXPECT_FALSE(loop.state.complete);
  // Wider than one tear step (max_step_mm 0.15 by default on this unit sheet): not the last step.
  r = tear_step(loop.m, loop.path, loop.state, pull, loop.t, loop.cs, loop.log);
  EXPECT_FALSE(r.ligament_broke);
  EXPECT_FALSE(loop.state.complete);
  loop.t.max_step_mm = 0.3;  // a tear stepping 0.3 mm: the gap is its last step
  r = tear_step(loop.m, loop.path, loop.state, pull, loop.t, loop.cs, loop.log);
  EXPECT_TRUE(r.ligament_broke);
  EXPECT_TRUE(r.advanced);
  EXPECT_TRUE(r.completed);
  EXPECT_TRUE(loop.state.complete);
  EXPECT_EQ(loop.state.count(TearEvent::Completed), 1u);
  EXPECT_NEAR(loop.tip().x(), 5.3, 0.05) << "straight through the ligament";
  EXPECT_NEAR(loop.tip().y(), 3.4, 0.05) << "onto the first side's lip";
  EXPECT_TRUE(cut::test::sound(loop.sheet));
}

TEST(Ligament, ATearFarFromItsStartIsHeldAndRunsOnByTheFlapForce) {
  LoopedTear loop(1.5);
  const Vec3 before = loop.tip();
  const Ligament l = own_ligament(loop.state.trail, before);
  ASSERT_TRUE(l.found) << "the rule is asked, and declines";
  EXPECT_GT(l.width_mm, 1.3);
  // Just under F_c: the 1.5 mm ligament holds 13.65 mN; nothing tears.
  TearStepReport r =
      tear_step(loop.m, loop.path, loop.state, Vec3(0.0, -9.7, 0.0), loop.t, loop.cs, loop.log);
  EXPECT_FALSE(r.ligament_broke);
  EXPECT_FALSE(r.advanced);
  EXPECT_EQ((loop.tip() - before).norm(), 0.0);
  // Over F_c the flap-force rule runs the tear one step, not through to its start.
  r = tear_step(loop.m, loop.path, loop.state, Vec3(0.0, -12.0, 0.0), loop.t, loop.cs, loop.log);
  EXPECT_FALSE(r.ligament_broke);
  EXPECT_FALSE(loop.state.complete);
  EXPECT_LE(r.advance_mm, loop.t.max_step_mm + 1e-12);
  EXPECT_TRUE(cut::test::sound(loop.sheet));
}

}  // namespace
}  // namespace phaco::tear
