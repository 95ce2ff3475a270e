// A tool pressing the rhexis rim in the steps after the capsulorhexis (procedures/scene/rim_tear,
// issue 20 item 1). A level-0 capsule is opened by the scripted capsulorhexis (a round 5.2 mm
// opening, a smooth rim), optionally nicked, and carried into a sculpting step whose probe is held
// upright and pushed out through the opening against the rim at −x to a chosen depth δ: the rim
// pushes back k·δ; a smooth rim tears at capsule.rim_strength_mn, a nicked one at the tear
// resistance F_c; a tear that runs to the equator fails the step and the procedure, named.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <optional>
#include <string>
#include <vector>

#include "engine/io/tool_shape.hpp"
#include "engine/io/track.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/procedure/carry.hpp"
#include "procedures/procedure/procedure_run.hpp"
#include "procedures/rhexis/scripted_rhexis.hpp"
#include "procedures/scene/capsule_cutting.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/rim_tear.hpp"
#include "procedures/scene/scene.hpp"
#include "systems/lens_tools/cell_dynamics.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

Scenario sculpting_level0() {
  Scenario s = test::repo_scenario("phaco_sculpting_expert.json");
  s.eye.level = 0;
  return s;
}

struct Opened {
  CarriedState carried;
  double rim_mm = 0;  // where the rim crosses −x, from the axis
  bool notch_is_sharp = false;
};

// The capsule's scene on the carried eye, one frame long, and its cut mesh.
struct CarriedScene {
  std::unique_ptr<Scene> scene;
  CapsuleCutting* cc = nullptr;
  std::optional<cut::CutMesh> mesh;
};

CarriedScene carried_scene(const CarriedState* carried) {
  Scenario s = sculpting_level0();
  s.duration_s = s.dt_s;
  SceneOptions opt = test::scene_options();
  opt.carried = carried;
  CarriedScene c;
  c.scene = build_scene(s, opt);
  const Entity capsule = *c.scene->body(BodyPart::Capsule);
  c.cc = &c.scene->world.at<CapsuleCutting>(capsule);
  c.mesh.emplace(cut::CutMesh{
      c.scene->world.at<Particles>(capsule), c.scene->world.at<Triangles>(capsule),
      c.scene->world.at<CapsuleSprings>(capsule).springs, c.cc->topology, c.cc->material});
  return c;
}

// The rim vertex nearest the −x axis (the scripted rhexis's flap and the tear's closing are
// near +x).
uint32_t rim_vertex_at_minus_x(const cut::CutMesh& m) {
  uint32_t best_v = 0;
  double best = 1e9;
  for (const RimEdge& e : rim_edges(m)) {
    for (uint32_t v : {e.a, e.b}) {
      const Vec3 x = cut::particle_position(m.particles, v);
      if (x.x() < 0 && std::abs(x.y()) < best) best = std::abs(x.y()), best_v = v;
    }
  }
  return best_v;
}

// The scripted capsulorhexis on a fresh level-0 capsule (a 5.2 mm opening), carried as a procedure
// carries it; then, if asked, a 0.4 mm radial nick cut from its rim at −x, carried again.
Opened opened_capsule(bool nick) {
  Opened o;
  {
    CarriedScene fresh = carried_scene(nullptr);
    CapsuleCutting& cc = *fresh.cc;
    EXPECT_TRUE(rhexis::run_scripted_rhexis(*fresh.mesh, {}, cc.tear, cc.cut).opening.complete);
    cc.cut_segments = 1;  // carried as a torn capsule
    carry_out(*fresh.scene, o.carried);
  }
  CarriedScene opened = carried_scene(&o.carried);
  cut::CutMesh& m = *opened.mesh;
  const uint32_t rim_vertex = rim_vertex_at_minus_x(m);
  const Vec3 from = cut::particle_position(m.particles, rim_vertex);
  o.rim_mm = -from.x();
  if (!nick) return o;
  CapsuleCutting& cc = *opened.cc;
  cut::CutPath path;
  path.hint_triangle = m.topology.vertex_triangle[rim_vertex];
  cut::cut_towards(m, path, from, cc.cut, cc.log);
  uint32_t hint = 0;
  for (const double d : {0.2, 0.4}) {
    const Vec3 to = rhexis::surface_below(m, from.x() - d, from.y(), hint, cc.cut.snap);
    cut::cut_towards(m, path, to, cc.cut, cc.log);
  }
  o.notch_is_sharp = path.tip != kInvalidIndex && membrane_angle_deg(m, path.tip) > 270.0;
  cc.cut_segments = 1;
  o.carried = {};
  carry_out(*opened.scene, o.carried);
  return o;
}

// The sculpting step's probe upright (shaft along +z), from the opening's centre out along −x
// until its section reaches `depth_mm` past the rim, held there; no ultrasound.
Scenario pushed_probe(const Opened& o, double depth_mm) {
  Scenario s = sculpting_level0();
  const double r = 0.5 * eye::default_eye_params().get("tools.phaco_tip_diameter_mm");
  const double x = -(o.rim_mm - r + depth_mm);
  for (HandTrack& h : s.hands) {
    if (h.tool != ToolKind::PhacoProbe) continue;
    h.track = {{0.0, Vec3(0.0, 0.0, 0.3), Quat::Identity(), 0, 0},
               {0.3, Vec3(x, 0.0, 0.0), Quat::Identity(), 0, 0},
               {0.5, Vec3(x, 0.0, 0.0), Quat::Identity(), 0, 0}};
  }
  s.duration_s = 0.5;
  return s;
}

std::unique_ptr<Scene> run_on(const Scenario& s, const CarriedState& carried) {
  SceneOptions opt = test::scene_options();
  opt.carried = &carried;
  auto scene = build_scene(s, opt);
  for (uint64_t f = 0; f < s.frame_count(); ++f) step(*scene);
  return scene;
}

const RimTears& rim_of(Scene& scene) {
  return scene.world.at<CapsuleCutting>(*scene.body(BodyPart::Capsule)).rim;
}

// The one tear the press started; null (and a failure) unless there is exactly one.
const RimTear* only_tear(Scene& scene) {
  const std::vector<RimTear>& tears = rim_of(scene).tears;
  EXPECT_EQ(tears.size(), 1u);
  return tears.size() == 1 ? &tears[0] : nullptr;
}

TEST(RimTear, AProbePressingASmoothRimBelowItsStrengthTearsNothing) {
  const Opened o = opened_capsule(false);
  auto scene = run_on(pushed_probe(o, 1.0), o.carried);
  const RimTears& rim = rim_of(*scene);
  const double k = eye::default_eye_params().get("capsule.rim_stiffness_mn_mm");
  // The rim was pressed 1 mm (measured in the rim's plane, which the dome tilts by 15°).
  EXPECT_NEAR(rim.max_force_mn, k * 1.0, 0.05 * k);
  EXPECT_GT(rim.pressing_frames, 10u);
  EXPECT_TRUE(rim.tears.empty());
  EXPECT_EQ(scene->world.at<CapsuleCutting>(*scene->body(BodyPart::Capsule)).topology_changes, 0u);
  const DrillReport r = drill_report(*scene);
  EXPECT_EQ(r.metrics.value("rim.tears", -1), 0);
  EXPECT_TRUE(r.complications.empty());
}

TEST(RimTear, AProbePressingASmoothRimAboveItsStrengthTearsItToTheEquator) {
  const Opened o = opened_capsule(false);
  auto scene = run_on(pushed_probe(o, 2.5), o.carried);
  const RimTear* t = only_tear(*scene);
  ASSERT_NE(t, nullptr);
  EXPECT_FALSE(t->notched);
  EXPECT_GE(t->start_force_mn, eye::default_eye_params().get("capsule.rim_strength_mn"));
  // It started at the rim pressed and ran out along the push, to the capsule's outer radius.
  EXPECT_NEAR(t->origin.x(), -o.rim_mm, 0.3);
  EXPECT_GT(-t->outward.x(), 0.9);
  EXPECT_TRUE(t->to_equator);
  EXPECT_GT(t->length_mm, 1.5);
  const DrillReport r = drill_report(*scene);
  EXPECT_EQ(r.metrics.value("rim.tears_to_equator", 0), 1);
  ASSERT_EQ(r.complications.size(), 1u);
  EXPECT_NE(r.complications[0]["name"].get<std::string>().find("radial tear to the equator"),
            std::string::npos);
  EXPECT_LE(r.score, 40.0);
  bool started = false, equator = false;
  for (const auto& e : r.events) {
    started |= e["kind"] == "rim_tear";
    equator |= e["kind"] == "rim_tear_to_equator";
  }
  EXPECT_TRUE(started && equator);
}

// A nick is a tear begun: pressed 0.6 mm (≈ 40 mN, far below a smooth rim's strength) it runs.
TEST(RimTear, ANickedRimTearsAtTheTearResistance) {
  const Opened o = opened_capsule(true);
  ASSERT_TRUE(o.notch_is_sharp);
  auto scene = run_on(pushed_probe(o, 0.6), o.carried);
  const RimTear* t = only_tear(*scene);
  ASSERT_NE(t, nullptr);
  EXPECT_TRUE(t->notched &&
              t->start_force_mn < 0.5 * eye::default_eye_params().get("capsule.rim_strength_mn"));
  // The push's stretch is spent after δ − F_c/k of tear, to within a tear step (0.15 mm): short
  // of the equator.
  const RimTearSettings& s = rim_of(*scene).settings;
  EXPECT_NEAR(t->advance_mm, t->pushed_mm - s.notched_strength_mn / s.stiffness_mn_mm, 0.15);
  EXPECT_GT(t->pushed_mm, 0.3);  // the probe sits in the nick, wedging its lips apart
  EXPECT_FALSE(t->to_equator);
  EXPECT_TRUE(drill_report(*scene).complications.empty());
}

// A bent chopper presses the rim with its shaft, 1 mm beside its tip (engine/io/tool_shape.hpp):
// turned so that its bend points along −x, its tip just reaching the rim while its shaft is 1 mm
// past it, the rim feels the shaft's 1 mm. Measured on the tip's line it felt nothing.
TEST(RimTear, ABentChopperPressesTheRimWithItsShaftNotItsTip) {
  const Opened o = opened_capsule(false);
  Scenario s = test::repo_scenario("nucleus_removal_expert.json");
  s.eye.level = 0;
  const double r = lens_tools::HookSettings{}.radius_mm;
  const Quat bend_to_minus_x(Eigen::AngleAxisd(0.5 * std::numbers::pi, Vec3::UnitZ()));
  ASSERT_LT((bend_to_minus_x * shaft_offset_local(ToolKind::Chopper) - Vec3(-kChopperBendMm, 0, 0))
                .norm(),
            1e-12);
  const double tip_x = -(o.rim_mm - r);  // the tip's section just at the rim
  for (HandTrack& h : s.hands) {
    if (h.tool == ToolKind::Chopper)
      h.track = {{0.0, Vec3(0.0, 0.0, 0.3), bend_to_minus_x, 0, 0},
                 {0.3, Vec3(tip_x, 0.0, 0.0), bend_to_minus_x, 0, 0},
                 {0.5, Vec3(tip_x, 0.0, 0.0), bend_to_minus_x, 0, 0}};
    else  // the probe waits in the opening's middle
      h.track = {{0.0, Vec3(0.0, 0.0, 0.3), Quat::Identity(), 0, 0}};
  }
  s.duration_s = 0.5;
  auto scene = run_on(s, o.carried);
  const RimTears& rim = rim_of(*scene);
  const double k = eye::default_eye_params().get("capsule.rim_stiffness_mn_mm");
  EXPECT_NEAR(rim.max_force_mn, k * kChopperBendMm, 0.1 * k);
  EXPECT_TRUE(rim.tears.empty());  // 1 mm on a smooth rim is below its strength
}

// A drill alone starts with a whole capsule: no opening, no rim, nothing torn or reported, however
// far the probe goes.
TEST(RimTear, ADrillAloneHasNoRimToTear) {
  Opened whole;
  whole.rim_mm = 2.6;
  auto scene = run_on(pushed_probe(whole, 2.5), CarriedState{});
  EXPECT_TRUE(rim_of(*scene).rim.empty());
  EXPECT_TRUE(rim_of(*scene).tears.empty());
  const DrillReport r = drill_report(*scene);
  EXPECT_FALSE(r.metrics.contains("rim.max_force_mN"));
  EXPECT_TRUE(r.complications.empty());
}

TEST(RimTear, ATearToTheEquatorFailsTheProcedureAndSaysWhy) {
  const Opened o = opened_capsule(false);
  Procedure p;
  p.source = "test procedure";
  p.steps = {pushed_probe(o, 2.5), test::repo_scenario("nucleus_removal_expert.json")};
  p.steps[1].eye.level = 0;
  ProcedureState state = begin_procedure(p);
  state.carried = o.carried;
  auto scene = start_step(state, test::scene_options());
  for (uint64_t f = 0; f < scene->scenario.frame_count(); ++f) step(*scene);
  finish_step(state, *scene, 0.0);
  ASSERT_TRUE(procedure_done(state));
  EXPECT_TRUE(state.report.failed);
  EXPECT_NE(state.report.failure.find("phaco_sculpting: radial tear to the equator"),
            std::string::npos)
      << state.report.failure;
  EXPECT_EQ(state.report.not_run, std::vector<std::string>{"nucleus_removal"});
}

}  // namespace
}  // namespace phaco
