// Cutting and tearing in the running scene (procedures/scene/capsule_cutting): the demo's
// cystotome cuts the capsule, the forceps tear the flap round until the disc comes free; the
// membrane keeps its invariants (bowtie vertices included, area and angle bounds on in the deformed
// and the rest shape), the result does not depend on the thread count, and the tear's
// events are recorded in order.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>

#include "engine/core/error.hpp"
#include "engine/io/track.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/topology_check/topology_check.hpp"
#include "tests/support/capsule_invariants.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

Scenario demo() {
  return test::repo_scenario("capsulorhexis_demo.json");
}

std::unique_ptr<Scene> run_all(const Scenario& s, int threads) {
  return test::run_to_end(s, threads);
}

TEST(CapsuleCutting, TheDemoCutsAndTearsTheCapsuleAndKeepsItSound) {
  auto scene = run_all(demo(), 1);
  const Entity capsule = *scene->body(BodyPart::Capsule);
  const CapsuleCutting* cc = scene->world.get<CapsuleCutting>(capsule);
  ASSERT_NE(cc, nullptr);
  EXPECT_GT(cc->cut_segments, 50u) << "the cystotome's radial cut";
  EXPECT_GT(cc->tear_state.advances, 10u) << "the forceps tore the flap";
  Particles& p = scene->world.at<Particles>(capsule);
  Triangles& tr = scene->world.at<Triangles>(capsule);
  CapsuleSprings& cp = scene->world.at<CapsuleSprings>(capsule);
  const CapsuleSolver& solver = scene->world.at<CapsuleSolver>(capsule);
  // The invariants in both shapes, each at its bounds (tests/support/capsule_invariants.hpp).
  CapsuleCutting& c = scene->world.at<CapsuleCutting>(capsule);
  EXPECT_TRUE(test::capsule_sound(p, tr, cp.springs, c));
  const cut::CutMesh m{p, tr, cp.springs, c.topology, c.material};
  EXPECT_EQ(cut::check_topology(m), "");
  EXPECT_EQ(solver.state.status.divergences, 0u);
  // The physics sees every particle the cut made.
  EXPECT_EQ(solver.forces.fx.size(), p.slots.size());
  EXPECT_EQ(cp.glue.x.size(), p.slots.size());
  EXPECT_EQ(cp.graph.particle_count(), p.slots.size());
  // A run-out is warned before it is recorded.
  bool warned = false;
  for (const auto& e : cc->tear_state.events) {
    if (e.kind == tear::TearEvent::RunoutWarning) warned = true;
    if (e.kind == tear::TearEvent::RadialTearout) {
      EXPECT_TRUE(warned) << "tear-out without a warning first";
    }
  }
  // The demo's forceps close the circle: the disc comes free, round and about the target size.
  const nlohmann::json j = capsule_cutting_summary(*scene);
  ASSERT_TRUE(j["opening_complete"].get<bool>());
  EXPECT_NEAR(j["opening_diameter_mm"].get<double>(), 5.0, 0.4);
  EXPECT_GT(j["opening_circularity"].get<double>(), 0.85);
  EXPECT_LT(j["opening_centering_mm"].get<double>(), 0.4);
  EXPECT_EQ(j["radial_tearouts"].get<uint64_t>(), 0u);
  EXPECT_EQ(j["cut_segments"].get<uint64_t>(), cc->cut_segments);
}

// The held flap folds at the tear resistance after the frame's edits, so the dynamics always start
// from a held pull of at most F_c. The demo's first quarter has a frame (t = 3.79 s) whose two tear
// steps run through the held particle's fan: folded before the edits, its new springs kept their
// own rest lengths and the dynamics started from 26.7 mN (a one-frame spike of up to 1.48·F_c in
// the forceps' force, depending on how the dynamics relaxed it).
TEST(CapsuleCutting, TheDynamicsStartFromAHeldPullAtMostTheTearResistance) {
  Scenario s = demo();
  s.duration_s = 4.0;  // the cut, the grasp and the tear's first steps
  auto scene = build_scene(s, test::scene_options());
  const CapsuleCutting& cc = scene->world.at<CapsuleCutting>(*scene->body(BodyPart::Capsule));
  const double fc = cc.tear.threshold_mn;
  const auto frames = static_cast<uint64_t>(std::llround(s.duration_s / s.dt_s));
  uint32_t folded = 0, folded_with_tear_steps = 0;
  for (uint64_t f = 0; f < frames; ++f) {
    step(*scene);
    EXPECT_LE(cc.held_pull_mn, fc * (1.0 + 1e-4)) << "frame " << f << ", t " << (f + 1) * s.dt_s;
    if (cc.flap_force_mn > fc) ++folded, folded_with_tear_steps += cc.tear_steps_last_frame > 0;
  }
  EXPECT_GT(folded, 5u) << "the flap pulled harder than F_c and folded";
  EXPECT_GT(folded_with_tear_steps, 0u) << "in frames where the tear ran too";
}

TEST(CapsuleCutting, ForcepsClosingBetweenVerticesHoldATemporaryVertexAndRemoveIt) {
  // The demo's grasp points are mesh vertices; moved off them, each grasp inserts a vertex under
  // the tip (seed 000 Fig. 9), removed once the forceps have let go (unless a cut went through it).
  Scenario s = demo();
  for (auto& hand : s.hands) {
    if (hand.tool != ToolKind::Forceps) continue;
    for (auto& sample : hand.track) sample.pos += Vec3(0.043, 0.027, 0.0);
  }
  auto scene = run_all(s, 1);
  const Entity capsule = *scene->body(BodyPart::Capsule);
  CapsuleCutting& cc = scene->world.at<CapsuleCutting>(capsule);
  RecordProperty("temporary_vertices", std::to_string(cc.temporary_vertices));
  RecordProperty("removed", std::to_string(cc.temporary_removed));
  EXPECT_GE(cc.temporary_vertices, 1u);
  EXPECT_EQ(cc.temporary_removed + cc.temporary_kept, cc.temporary_vertices) << "every one let go";
  for (const auto& g : cc.forceps) EXPECT_FALSE(g.held());
  Particles& p = scene->world.at<Particles>(capsule);
  Triangles& tr = scene->world.at<Triangles>(capsule);
  CapsuleSprings& cp = scene->world.at<CapsuleSprings>(capsule);
  EXPECT_TRUE(test::capsule_sound(p, tr, cp.springs, cc));
  const cut::CutMesh m{p, tr, cp.springs, cc.topology, cc.material};
  EXPECT_EQ(cut::check_topology(m), "");
  EXPECT_EQ(scene->world.at<CapsuleSolver>(capsule).state.status.divergences, 0u);
}

TEST(CapsuleCutting, SameResultOnOneTwoAndFourThreads) {
  Scenario s = demo();
  s.duration_s = 6.0;  // the cystotome's cut and the first quarter of the tear
  auto one = run_all(s, 1);
  auto two = run_all(s, 2);
  auto four = run_all(s, 4);
  EXPECT_EQ(state_hash(*one), state_hash(*two));
  EXPECT_EQ(state_hash(*one), state_hash(*four));
}

// Steps the demo frame by frame; after every frame that changed the capsule's topology (and every
// deferred compaction) the membrane keeps its invariants on the deformed scene mesh, and the
// incrementally patched physics (capsule.springs) is what a fresh build gives: every graph row
// equal as a set, the blocks and their tail visiting every spring exactly once.
void expect_sound_after_every_cut(Scenario s, double compact_fraction, uint32_t compact_min_springs,
                                  uint64_t& compactions) {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  auto scene = build_scene(s, o);
  const Entity capsule = *scene->body(BodyPart::Capsule);
  CapsuleCutting& cc = scene->world.at<CapsuleCutting>(capsule);
  cc.compact_fraction = compact_fraction, cc.compact_min_springs = compact_min_springs;
  const auto frames = static_cast<uint64_t>(std::llround(s.duration_s / s.dt_s));
  uint64_t changes = 0, checked = 0;
  for (uint64_t f = 0; f < frames; ++f) {
    step(*scene);
    if (cc.topology_changes == changes && cc.compactions == compactions) continue;
    changes = cc.topology_changes, compactions = cc.compactions;
    const Particles& p = scene->world.at<Particles>(capsule);
    const Triangles& tr = scene->world.at<Triangles>(capsule);
    const CapsuleSprings& sp = scene->world.at<CapsuleSprings>(capsule);
    ASSERT_TRUE(test::capsule_sound(p, tr, sp.springs, cc)) << "frame " << f;
    ASSERT_EQ(
        topology_check::check_spring_structure(sp.springs, sp.blocks, sp.graph, p.slots.size()), "")
        << "frame " << f;
    ASSERT_EQ(sp.glue.x.size(), p.slots.size()) << "frame " << f;
    ++checked;
  }
  EXPECT_GT(checked, 50u) << "the demo cuts and tears";
  CapsuleSprings& sp = scene->world.at<CapsuleSprings>(capsule);
  const cut::CutMesh m{scene->world.at<Particles>(capsule), scene->world.at<Triangles>(capsule),
                       sp.springs, cc.topology, cc.material};
  EXPECT_EQ(cut::check_topology(m), "");
}

TEST(CapsuleCutting, PatchedPhysicsEqualsAFreshBuildAfterEveryCutFrame) {
  Scenario s = demo();
  s.duration_s = 8.0;  // the cystotome's cut and the tear's first quarters
  uint64_t compactions = 0;
  expect_sound_after_every_cut(s, 0.125, 1024, compactions);
}

TEST(CapsuleCutting, DeferredCompactionHappensAndKeepsThePhysicsSound) {
  Scenario s = demo();
  s.duration_s = 8.0;
  uint64_t compactions = 0;
  expect_sound_after_every_cut(s, 0.002, 16, compactions);  // due after a few dozen changed springs
  EXPECT_GT(compactions, 2u);
}

// The demo's cystotome through its radial stroke, lifted `lift_mm` off its track for a tenth of a
// second mid-stroke (a hand's tremor, or a hesitation), with the y it has reached there.
std::unique_ptr<Scene> cut_with_a_lift(double lift_mm) {
  Scenario s = demo();
  s.duration_s = 2.5;  // through the stroke and the lift-off at its end
  for (HandTrack& h : s.hands) {
    if (h.tool != ToolKind::Cystotome) continue;
    const auto at = [&h](double t) { return sample_track(h.track, t); };
    TrackSample up, down;
    up.t = 1.45, up.pos = at(1.45).pos + Vec3(0, 0, lift_mm), up.quat = at(1.45).quat;
    down.t = 1.5, down.pos = at(1.5).pos, down.quat = at(1.5).quat;
    auto it = std::find_if(h.track.begin(), h.track.end(),
                           [](const TrackSample& x) { return x.t > 1.45; });
    it = h.track.insert(it, up);
    h.track.insert(it + 1, down);
  }
  return run_all(s, 1);
}

// A blade lifted less than its own tip length (tools.cystotome_tip_mm, 0.3 mm) is still in its
// hole: the stroke goes on, and the whole cut is the flap the forceps will tear. Lifted clear of
// the capsule, the stroke ends there and the cut resumes as a new stroke.
TEST(CapsuleCutting, AStrokeSurvivesALiftShorterThanTheBlade) {
  for (const double lift : {0.15, 0.6}) {
    auto scene = cut_with_a_lift(lift);
    const CapsuleCutting& cc = scene->world.at<CapsuleCutting>(*scene->body(BodyPart::Capsule));
    ASSERT_NE(cc.flap.tip, kInvalidIndex) << "lift " << lift;
    EXPECT_GT(cc.cut_segments, 50u) << "lift " << lift;
    if (lift < 0.3) {
      EXPECT_EQ(cc.flap.segments, cc.cut_segments) << "one stroke";
    } else {
      EXPECT_LT(cc.flap.segments, cc.cut_segments) << "the stroke ended at the lift";
    }
  }
}

TEST(CapsuleCutting, CanBeSwitchedOffAndRejectsAnUnknownRule) {
  Scenario s = demo();
  s.duration_s = 2.5;  // through the cystotome's stroke
  s.methods["capsule.cutting"] = "off";
  auto scene = run_all(s, 1);
  const Entity capsule = *scene->body(BodyPart::Capsule);
  EXPECT_EQ(scene->world.get<CapsuleCutting>(capsule), nullptr);
  Scenario bad = demo();
  bad.methods["capsule.tear_rule"] = "scissors";
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  EXPECT_THROW(build_scene(bad, o), InputError);
}

}  // namespace
}  // namespace phaco
