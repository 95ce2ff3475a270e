// The procedure mode (issue 20 item 1, docs/procedures.md): the drills in one eye. The scripted
// expert's procedure runs end to end and every step scores as its drill scores a scene built on
// the same carried eye; the incision the trainee cut is the next step's main port (turn the cut
// and the port turns with it); the torn rhexis is the next step's opening; the sculpted trench is
// the nucleus's groove; a complication fails the procedure, says why and leaves the rest unrun.
// Level 0 meshes (level 1 for the whole expert) and shortened steps keep it to seconds.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>
#include <vector>

#include "components/body.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "engine/io/tool_shape.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/procedure/procedure_run.hpp"
#include "procedures/scene/drill_metrics.hpp"
#include "procedures/scene/tool_ports.hpp"
#include "procedures/trainer/live_ports.hpp"
#include "tests/support/scene_run.hpp"

namespace phaco {
namespace {

SceneOptions options() {
  SceneOptions o;
  o.cache_dir = test::scene_cache_dir();
  return o;
}

// Steps in one eye at `level` (0 unless said); a positive duration cuts the step short.
Procedure procedure_of(std::vector<std::pair<Scenario, double>> steps, int level = 0) {
  Procedure p;
  p.source = "test procedure";
  for (auto& [s, duration] : steps) {
    s.eye.level = level;
    if (duration > 0) s.duration_s = duration;
    p.steps.push_back(s);
  }
  return p;
}

// The incision expert's pass turned about the optical axis (positive: anticlockwise from above,
// towards 12 o'clock).
Scenario turned_incision(double degrees) {
  Scenario s = test::repo_scenario("corneal_incision_expert.json");
  const Quat turn(Eigen::AngleAxisd(degrees * std::numbers::pi / 180.0, Vec3::UnitZ()));
  for (HandTrack& h : s.hands) {
    for (TrackSample& t : h.track) {
      t.pos = turn * t.pos;
      t.quat = (turn * t.quat).normalized();
    }
  }
  return s;
}

TEST(Procedure, TheExpertRunsEndToEndAndEachStepScoresAsItsDrillOnTheCarriedEye) {
  // Level 1, as the expert's procedure file: on the level-0 mesh the expert's rhexis misses its
  // size target (4.72 mm, under 5.0), and on so small an opening the later steps' shafts press
  // its rim at about its strength, so whether they nick it turns on rounding (the implicit
  // solve's preconditioner flips it; docs/procedures.md, "The rim's margin").
  const Procedure p = procedure_of({{test::repo_scenario("corneal_incision_expert.json"), 0},
                                    {test::repo_scenario("capsulorhexis_expert.json"), 0},
                                    {test::repo_scenario("phaco_sculpting_expert.json"), 0},
                                    {test::repo_scenario("nucleus_removal_expert.json"), 8.0}},
                                   1);
  ProcedureState state = begin_procedure(p);
  std::vector<CarriedState> carried_in;
  double worst_off_port = 0;
  int pivoted_frames = 0;
  std::vector<double> main_port_force;  // per step: the main-port (right) tool's, mN
  while (!procedure_done(state)) {
    carried_in.push_back(state.carried);
    auto scene = start_step(state, options());
    const auto& pivot = scene->track_pivots[static_cast<size_t>(Hand::Right)];
    EXPECT_EQ(pivot.has_value(), scene->scenario.drill != Drill::CornealIncision);
    main_port_force.push_back(0.0);
    for (uint64_t f = 0; f < scene->scenario.frame_count(); ++f) {
      step(*scene);
      for (size_t i = 0; i < scene->tools.size(); ++i) {
        const Entity e = scene->tools[i];
        const ToolState& pose = scene->world.at<ToolState>(e);
        if (scene->world.at<Tool>(e).hand != Hand::Right) continue;
        if (const PortsRecord* ports = ports_record(*scene); ports && i < kMaxPortTools)
          main_port_force.back() = std::max(main_port_force.back(), ports->force_mn[i]);
        // The main-port hand's track keeps its tip and aims its shaft through the cut port: the
        // drawn shaft's axis, beside the tip by the cystotome's bent point (engine/io/tool_shape).
        if (!pivot || (pose.pos - pivot->to.centre_mm).dot(pivot->to.axis) < 1.0) continue;
        const ShaftAxis axis = shaft_axis(pose, scene->world.at<Tool>(e).kind);
        const Vec3 d = pivot->to.centre_mm - axis.point;
        worst_off_port =
            std::max(worst_off_port, (d - d.dot(axis.direction) * axis.direction).norm());
        ++pivoted_frames;
      }
    }
    finish_step(state, *scene, 0.0);
  }
  const ProcedureReport& r = state.report;
  ASSERT_EQ(r.steps.size(), 4u) << r.failure;
  EXPECT_FALSE(r.failed) << r.failure;
  EXPECT_GT(pivoted_frames, 100);
  EXPECT_LT(worst_off_port, 1e-6) << "mm from the carried port's centre";
  // So the later experts' tools do not press on the cut tunnel: made for the drill's default
  // port they pressed it 93-112 mN and turned the globe 4.6-5.3° (capsulorhexis, sculpting);
  // alone, in their own port, ~1 mN. Nor the nucleus removal's chopper on its side port: down in
  // the trench it met the uncut lens's spring and pressed the port 146 mN, turning the globe 8.5°
  // (tool_ports: the lens is no boundary for the probe and the chopper).
  for (size_t i = 1; i < 4; ++i) {
    EXPECT_LT(main_port_force[i], 10.0) << i;
    EXPECT_LT(r.steps[i].run.metrics.value("ports.max_force_mN", 1e9), 10.0) << i;
    EXPECT_LT(r.steps[i].run.metrics.value("globe.max_rotation_deg", 1e9), 1.0) << i;
  }
  // The later steps' tools work through the torn opening without tearing its rim (rim_tear.hpp):
  // the sculpting probe's shaft passes under the subincisional rim, pressing it below a smooth
  // rim's strength, and the expert's rim has no nick.
  const double rim_strength = eye::default_eye_params().get("capsule.rim_strength_mn");
  for (size_t i = 2; i < 4; ++i) {
    const nlohmann::json& m = r.steps[i].run.metrics;
    EXPECT_EQ(m.value("rim.tears", -1), 0) << i;
    EXPECT_EQ(m.value("rim.notches", -1), 0) << i;
    EXPECT_LT(m.value("rim.max_force_mN", 1e9), rim_strength) << i;
  }
  // The probe comes in through the cut main port, whose inner opening lies over the pupil 0.01 mm
  // from the endothelium: passing through its own wound is not the endothelium (0.18 mm when it
  // counted; nucleus_removal_metrics leaves the wound out, as the corneal-stress event does).
  EXPECT_GE(r.steps[3].run.metrics.value("endothelium.min_distance_mm", 1e9), 1.0);
  double sum = 0;
  for (size_t i = 0; i < r.steps.size(); ++i) {
    const double score = r.steps[i].run.metrics.value("score", -1.0);
    sum += score;
    // The same step as a drill on its own, on the eye the procedure carried to it.
    SceneOptions o = options();
    o.carried = &carried_in[i];
    auto scene = build_scene(p.steps[i], o);
    for (uint64_t f = 0; f < p.steps[i].frame_count(); ++f) step(*scene);
    EXPECT_EQ(drill_report(*scene).score, score) << r.steps[i].run.drill;
    if (i < 3) {
      EXPECT_GE(score, 80.0) << r.steps[i].run.drill;  // the expert passes
    }
  }
  EXPECT_DOUBLE_EQ(r.total, sum / 4.0);
  // Every later step started from a carried port, opening and (for the nucleus) trench.
  EXPECT_TRUE(r.steps[1].carried_in.contains("main_port"));
  EXPECT_GT(r.steps[2].carried_in.value("rhexis_radius_mm", 0.0), 2.0);
  EXPECT_GT(r.steps[3].carried_in.value("lens_tets_removed", 0), 0);
  const nlohmann::json& fragments = r.steps[3].run.physics["lens_fragments"];
  const nlohmann::json& sculpted = r.steps[2].run.physics["lens_sculpting"];
  EXPECT_NEAR(fragments.value("grooved_volume_mm3", 0.0),
              sculpted.value("volume_removed_mm3", -1.0),
              1e-6 * sculpted.value("volume_removed_mm3", 0.0));
}

// The next step's main port is where the cut is: turn the incision 30° towards 12 o'clock (3 → 2
// o'clock) and the port turns with it.
TEST(Procedure, TheMainPortIsTheIncisionThatWasCut) {
  for (const double degrees : {0.0, 30.0}) {
    const Procedure p = procedure_of(
        {{turned_incision(degrees), 0}, {test::repo_scenario("capsulorhexis_expert.json"), 0.05}});
    ProcedureState state = begin_procedure(p);
    auto incision = start_step(state, options());
    for (uint64_t f = 0; f < incision->scenario.frame_count(); ++f) step(*incision);
    finish_step(state, *incision, 0.0);
    ASSERT_TRUE(state.carried.main_port) << degrees;
    const EyePort& cut = *state.carried.main_port;
    EXPECT_NEAR(cut.clock_hour, 3.0 - degrees / 30.0, 0.2) << degrees;
    auto rhexis = start_step(state, options());
    const PortsRecord* ports = ports_record(*rhexis);
    ASSERT_NE(ports, nullptr);
    const EyePort& main = ports->ports.front();
    EXPECT_EQ(main.name, "main");
    EXPECT_EQ(main.centre_mm, cut.centre_mm);
    EXPECT_NEAR(std::atan2(main.centre_mm.y(), main.centre_mm.x()) * 180.0 / std::numbers::pi,
                degrees, 3.0);
    EXPECT_NEAR(main.width_mm, eye::default_eye_params().get("tools.keratome_width_mm"), 0.3);
    EXPECT_GT(main.tunnel_length_mm, 1.0);
    EXPECT_GT(main.axis.dot(-main.centre_mm.normalized()), 0.5) << "the tunnel runs inward";
    // The trainer's mouse pivots the right hand's shaft in that same port.
    const auto pivots = desktop_ports(rhexis->scenario, &state.carried);
    ASSERT_TRUE(pivots[static_cast<size_t>(Hand::Right)]);
    EXPECT_EQ(pivots[static_cast<size_t>(Hand::Right)]->centre_mm, cut.centre_mm);
  }
}

// The opening the rhexis tore is the next step's: the sculpting scene's capsule has it, the disc
// taken out.
TEST(Procedure, TheTornRhexisIsTheNextStepsOpening) {
  const Procedure p = procedure_of({{test::repo_scenario("corneal_incision_expert.json"), 0},
                                    {test::repo_scenario("capsulorhexis_expert.json"), 0},
                                    {test::repo_scenario("phaco_sculpting_expert.json"), 0.05}});
  const ProcedureReport r = run_procedure(p, options());
  ASSERT_EQ(r.steps.size(), 3u) << r.failure;
  const double torn = r.steps[1].run.metrics.value("rhexis.diameter_mm", 0.0);
  ASSERT_GT(torn, 4.0);
  EXPECT_NEAR(2.0 * r.steps[2].carried_in.value("rhexis_radius_mm", 0.0), torn, 1e-9);
  // The capsule the sculpting step works in is the held one: fewer triangles than the fresh bag's
  // (the disc is out), and its opening measures as the one torn.
  const auto fresh = test::run_to_end(procedure_of({{p.steps[2], 0.01}}).steps[0], 1);
  uint64_t fresh_triangles = 0, carried_triangles = 0;
  for (const auto& [k, v] : element_counts(*fresh))
    if (k == "capsule.triangles") fresh_triangles = v;
  for (const auto& [k, v] : r.steps[2].run.elements)
    if (k == "capsule.triangles") carried_triangles = v;
  EXPECT_EQ(carried_triangles, r.steps[2].carried_in.value("capsule_triangles", 0u));
  EXPECT_LT(carried_triangles, fresh_triangles);
}

// A posterior capsule rupture in sculpting fails the procedure there, with the reason; the
// nucleus removal after it does not run and counts 0 in the total.
TEST(Procedure, AComplicationFailsTheProcedureAndSaysWhy) {
  Scenario plunge = test::repo_scenario("phaco_sculpting_expert.json");
  test::plunge_through_posterior_capsule(
      plunge, eye::default_eye_params().get("lens.posterior_half_thickness_mm"));
  const Procedure p = procedure_of({{test::repo_scenario("corneal_incision_expert.json"), 0},
                                    {plunge, 2.0},
                                    {test::repo_scenario("nucleus_removal_expert.json"), 1.0}});
  const ProcedureReport r = run_procedure(p, options());
  EXPECT_TRUE(r.failed);
  ASSERT_EQ(r.steps.size(), 2u);
  EXPECT_NE(r.failure.find("phaco_sculpting: posterior capsule rupture"), std::string::npos)
      << r.failure;
  EXPECT_EQ(r.not_run, std::vector<std::string>{"nucleus_removal"});
  const double s0 = r.steps[0].run.metrics.value("score", -1.0),
               s1 = r.steps[1].run.metrics.value("score", -1.0);
  EXPECT_LE(s1, 40.0);
  EXPECT_DOUBLE_EQ(r.total, (s0 + s1) / 3.0);
  const nlohmann::json j = to_json(r);
  EXPECT_TRUE(j["failed"].get<bool>());
  EXPECT_EQ(j["steps"].size(), 2u);
}

// An incision that never enters the anterior chamber leaves no port: the procedure stops there.
TEST(Procedure, AnIncisionThatNeverEntersFailsTheProcedure) {
  const Procedure p = procedure_of({{test::repo_scenario("corneal_incision_expert.json"), 0.3},
                                    {test::repo_scenario("capsulorhexis_expert.json"), 0.05}});
  const ProcedureReport r = run_procedure(p, options());
  EXPECT_TRUE(r.failed);
  EXPECT_NE(r.failure.find("did not enter the anterior chamber"), std::string::npos) << r.failure;
  EXPECT_EQ(r.not_run, std::vector<std::string>{"capsulorhexis"});
}

TEST(ProcedureFile, StepsOutOfOrderAreNamed) {
  const std::string dir = std::string(PHACO_SOURCE_DIR) + "/data/scenarios/";
  const std::string text = R"({"steps": [{"scenario": "capsulorhexis_expert.json"},
                                         {"scenario": "corneal_incision_expert.json"}]})";
  try {
    parse_procedure(text, "p.json", dir);
    FAIL() << "accepted steps out of order";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("p.json: steps[1].scenario: the steps go in the "
                                         "operation's order"),
              std::string::npos)
        << e.what();
  }
}

TEST(ProcedureFile, TheShippedExpertIsOneEye) {
  const Procedure p = load_procedure(std::filesystem::path(PHACO_SOURCE_DIR) /
                                     "data/procedures/cataract_expert.json");
  ASSERT_EQ(p.steps.size(), 4u);
  for (const Scenario& s : p.steps) EXPECT_EQ(s.eye, p.steps.front().eye);
  EXPECT_EQ(p.steps.front().eye.level, 1);
}

}  // namespace
}  // namespace phaco
