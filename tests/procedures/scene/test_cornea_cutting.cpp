// Cutting the cornea in the running scene (procedures/scene/cornea_cutting): a keratome track that
// repeats procedures/incision's scripted straight pass cuts the scene's cornea as the script cuts
// its own cornea sheet (same mesh measures); nothing but a keratome cuts; the result does not
// depend on the thread count; the cut mesh keeps item 4's invariants.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <vector>

#include "components/particles.hpp"
#include "components/triangles.hpp"
#include "engine/io/track.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/incision/cornea_sheet.hpp"
#include "procedures/incision/scripted_incision.hpp"
#include "procedures/scene/cornea_cutting.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/topology_check/topology_check.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

constexpr int kLevel = 3;  // the drill scenarios' level

// The scene's keratome track for a scripted straight pass: one frame before the start pose, then
// step_mm per frame along the axis to the script's advance, then withdrawn to the start.
Scenario pass_scenario(const corneal_incision::IncisionScript& script, double advance_mm) {
  Scenario s = test::repo_scenario("corneal_incision_demo.json");
  const eye::EyeParams params = eye::default_eye_params();
  const incision::CorneaSpheres sp = corneal_incision::cornea_spheres(params);
  const incision::KeratomeBlade b =
      incision::incision_start_blade(sp.anterior_centre_z, sp.anterior_radius_mm,
                                     sp.limbus_radius_mm, script.approach, script.shape);
  const incision::BladeFrame f = incision::blade_frame(b);
  const Quat q = incision::tool_quat_for_blade(f.d, f.l);
  const double v = script.step_mm / s.dt_s;  // mm/s: one step per frame
  const double t_in = s.dt_s + advance_mm / v;
  TrackSample a{0.0, f.tip - script.step_mm * f.d, q};
  TrackSample deepest{t_in, f.tip + advance_mm * f.d, q};
  TrackSample out{t_in + 0.2, f.tip - 0.5 * f.d, q};
  s.hands.clear();
  s.hands.push_back({Hand::Right, ToolKind::Keratome, {a, deepest, out}});
  s.duration_s = t_in + 0.25;
  return s;
}

TEST(CorneaCutting, TheSceneCutsAsTheScriptedPass) {
  const eye::EyeParams params = eye::default_eye_params();
  corneal_incision::IncisionScript script;
  script.approach = {3.0, 0.3, 15.0};
  script.shape = corneal_incision::eye_keratome(params);
  cut::MembraneSheet sheet = corneal_incision::make_cornea_sheet(params, kLevel);
  // The scene's cornea is anchored (rigid; its particles are not simulated), and the cutter's
  // merging along the path keeps anchored vertices: anchor the sheet too, so both cut alike.
  for (uint32_t i = 0; i < sheet.particles.slots.size(); ++i)
    sheet.particles.kind[i] = ParticleKind::Anchored, sheet.particles.inv_mass[i] = 0.0f;
  cut::CutMesh m = sheet.mesh();
  const corneal_incision::IncisionResult r = corneal_incision::run_scripted_incision(
      m, corneal_incision::cornea_spheres(params), script, cut::CutSettings{});
  ASSERT_TRUE(r.passed);

  auto scene = test::run_to_end(pass_scenario(script, r.advance_mm), 1);
  MeshIncision w;
  ASSERT_TRUE(measure_scene_incision(*scene, w));
  ASSERT_TRUE(w.outer_cut && w.inner_cut);
  EXPECT_TRUE(w.complete);
  RecordProperty("scene_width_mm", std::to_string(w.width_mm));
  RecordProperty("script_width_mm", std::to_string(r.outer.chord_mm));
  // The same cuts on the same mesh, up to the rounding of the track's interpolation: within
  // 0.01 mm and 0.2° (half the cutter's vertex snap, 0.02 mm, would already show).
  EXPECT_NEAR(w.width_mm, r.outer.chord_mm, 0.01);
  EXPECT_NEAR(w.clock_hour, r.mesh_clock_hour, 0.01);
  EXPECT_NEAR(w.limbus_distance_mm, r.mesh_limbus_distance_mm, 0.01);
  EXPECT_NEAR(w.iris_plane_angle_deg, r.mesh_entry_angle_deg, 0.2);
  EXPECT_NEAR(w.tunnel_length_mm, r.mesh_tunnel_length_mm, 0.01);
  // And the wound tracker's section measures, the approach's.
  EXPECT_NEAR(w.wound.entry_angle_deg, 15.0, 1e-6);
  EXPECT_NEAR(w.wound.width_mm, r.wound.width_mm, 1e-6);
  // The same mesh change as the script's, on the same mesh.
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  auto uncut = build_scene(pass_scenario(script, r.advance_mm), o);
  const Entity c0 = *uncut->body(BodyPart::Cornea);
  EXPECT_EQ(uncut->world.at<Triangles>(c0).slots.live_count(), r.triangles_before);
  const Entity cornea = *scene->body(BodyPart::Cornea);
  EXPECT_EQ(scene->world.at<Triangles>(cornea).slots.live_count() - r.triangles_before,
            r.triangles_after - r.triangles_before);
  EXPECT_EQ(scene->world.at<Particles>(cornea).slots.live_count() - r.particles_before,
            r.particles_after - r.particles_before);
}

// A hand's tremor lifts a blade that has just entered the cornea back off its surface, by less
// than the withdrawal margin (0.1 mm): the incision goes on, as wide as the pass without the lift.
TEST(CorneaCutting, ATremorLiftJustAfterEntryDoesNotEndTheIncision) {
  const eye::EyeParams params = eye::default_eye_params();
  corneal_incision::IncisionScript script;
  script.approach = {3.0, 0.3, 15.0};
  script.shape = corneal_incision::eye_keratome(params);
  const double advance_mm = 2.0;
  const Scenario plain = pass_scenario(script, advance_mm);
  Scenario lifted = plain;
  // 0.1 mm into the cut, the whole blade is raised 0.14 mm along the surface normal for two frames
  // (its tip then just clear of the surface: the old rule, "no longer touching", ended the cut).
  std::vector<TrackSample>& track = lifted.hands.front().track;
  const incision::CorneaSpheres sp = corneal_incision::cornea_spheres(params);
  const Vec3 n = (track.front().pos - Vec3(0, 0, sp.anterior_centre_z)).normalized();
  const double v = script.step_mm / plain.dt_s, t0 = plain.dt_s + 0.1 / v;
  const auto at = [&plain](double t) { return sample_track(plain.hands.front().track, t); };
  std::vector<TrackSample> lift;
  for (const double t : {t0, t0 + plain.dt_s, t0 + 2 * plain.dt_s, t0 + 3 * plain.dt_s}) {
    const ToolPose p = at(t);
    const bool up = t > t0 + 0.5 * plain.dt_s && t < t0 + 2.5 * plain.dt_s;
    lift.push_back({t, p.pos + (up ? 0.14 : 0.0) * n, p.quat});
  }
  track.insert(track.begin() + 1, lift.begin(), lift.end());
  MeshIncision a, b;
  auto one = test::run_to_end(plain, 1), two = test::run_to_end(lifted, 1);
  ASSERT_TRUE(measure_scene_incision(*one, a));
  ASSERT_TRUE(measure_scene_incision(*two, b));
  ASSERT_TRUE(a.outer_cut && b.outer_cut);
  EXPECT_GT(a.width_mm, 2.0);
  EXPECT_NEAR(b.width_mm, a.width_mm, 0.1) << "the lift ended the incision";
  EXPECT_TRUE(b.inner_cut && b.complete);
}

TEST(CorneaCutting, OnlyAKeratomeCuts) {
  Scenario s = test::repo_scenario("corneal_incision_expert.json");
  // The expert's track in the left hand's forceps (the drill's other tool): no blade in the scene.
  for (auto& hand : s.hands) hand.hand = Hand::Left, hand.tool = ToolKind::Forceps;
  auto scene = test::run_to_end(s, 1);
  const Entity cornea = *scene->body(BodyPart::Cornea);
  EXPECT_EQ(scene->world.get<CorneaCutting>(cornea), nullptr);
  MeshIncision w;
  EXPECT_FALSE(measure_scene_incision(*scene, w));
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  auto uncut = build_scene(s, o);
  const Entity c0 = *uncut->body(BodyPart::Cornea);
  EXPECT_EQ(scene->world.at<Triangles>(cornea).slots.live_count(),
            uncut->world.at<Triangles>(c0).slots.live_count());
  EXPECT_EQ(scene->world.at<Particles>(cornea).slots.live_count(),
            uncut->world.at<Particles>(c0).slots.live_count());
}

TEST(CorneaCutting, SameStateOnOneAndTwoThreadsAndTheMeshStaysSound) {
  const Scenario s = test::repo_scenario("corneal_incision_expert.json");
  auto one = test::run_to_end(s, 1);
  auto two = test::run_to_end(s, 2);
  EXPECT_EQ(state_hash(*one), state_hash(*two));
  const Entity cornea = *one->body(BodyPart::Cornea);
  CorneaCutting& cc = one->world.at<CorneaCutting>(cornea);
  EXPECT_TRUE(cc.done) << "the blade withdrew: the paths ended";
  EXPECT_GT(cc.segments, 0u);
  Particles& p = one->world.at<Particles>(cornea);
  Triangles& tr = one->world.at<Triangles>(cornea);
  const auto report = topology_check::check_membrane(p, tr, cc.springs);
  EXPECT_TRUE(report.ok()) << report.summary();
  const cut::CutMesh m{p, tr, cc.springs, cc.topology, cc.material};
  EXPECT_EQ(cut::check_topology(m), "");
  // Anchored stays anchored: the cut cornea does not move.
  for (uint32_t i = 0; i < p.slots.size(); ++i) {
    if (!p.slots.alive(i)) continue;
    EXPECT_EQ(p.inv_mass[i], 0.0f) << "particle " << i;
    if (p.inv_mass[i] != 0.0f) break;
  }
  MeshIncision w;
  ASSERT_TRUE(measure_scene_incision(*one, w));
  EXPECT_TRUE(w.complete);
  const TargetBand& tunnel = one->drill.targets.at("incision.tunnel_length_mm");
  const TargetBand& angle = one->drill.targets.at("incision.entry_angle_deg");
  EXPECT_GE(w.tunnel_length_mm, *tunnel.min);
  EXPECT_LE(w.entry_angle_deg, *angle.max);
}

}  // namespace
}  // namespace phaco
