#include <gtest/gtest.h>

#include <filesystem>

#include "components/particles.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "engine/core/rng.hpp"
#include "engine/schedule/parallel.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/method_settings.hpp"
#include "procedures/scene/run.hpp"
#include "procedures/scene/scene_inputs.hpp"
#include "tests/support/expect_invalid.hpp"

namespace phaco {
namespace {

std::filesystem::path cache_dir() {
  const char* env = std::getenv("PHACO_CACHE_DIR");
  return env ? std::filesystem::path(env)
             : std::filesystem::temp_directory_path() / "phaco-test-cache";
}

Scenario small_scenario(Drill drill = Drill::Capsulorhexis) {
  // The right hand holds a tool the drill allows (data/drills).
  const std::string right = drill == Drill::CornealIncision  ? "keratome"
                            : drill == Drill::PhacoSculpting ? "phaco_probe"
                                                             : "cystotome";
  const std::string text = R"({
    "drill": ")" + std::string(to_string(drill)) +
                           R"(",
    "eye": { "level": 0 },
    "dt_s": 0.01, "seed": 11, "duration_s": 0.5,
    "hands": {
      "left":  { "tool": "forceps", "track": [
        { "t": 0.0, "pos": [-1.0, 0.0, 3.5], "quat": [1, 0, 0, 0], "grip": 0.0 },
        { "t": 0.5, "pos": [-1.0, 0.5, 2.0], "quat": [0.7071, 0.7071, 0, 0], "grip": 1.0 } ] },
      "right": { "tool": ")" +
                           right + R"(", "track": [
        { "t": 0.0, "pos": [0.0, 0.0, 3.5], "quat": [1, 0, 0, 0] },
        { "t": 0.25, "pos": [0.0, 0.0, 1.9], "quat": [1, 0, 0, 0] } ] }
    } })";
  return parse_scenario(text, "small.json", ".");
}

// Parallel work with counter-based random numbers and an ordered reduction, standing in for the
// physics systems of later issues: its result must not depend on the thread count.
struct JitterProbe {
  std::vector<double> centroid_z;  // one per frame
};

std::vector<SystemDesc> jitter_systems(Scene& scene, JitterProbe& probe) {
  const Entity capsule = *scene.body(BodyPart::Capsule);
  const uint64_t seed = scene.scenario.seed;
  std::vector<SystemDesc> s;
  s.push_back({.name = "test_jitter",
               .phase = Phase::Dynamics,
               .reads = {"tools.pose"},
               .writes = {"capsule.particles"},
               .run = [&scene, capsule, seed](const FrameContext& ctx) {
                 Particles& p = scene.world.at<Particles>(capsule);
                 const CounterRng rng(seed, 3);
                 const float tool_z =
                     static_cast<float>(scene.world.at<ToolState>(scene.tools[1]).pos.z());
                 parallel_for(0, p.slots.size(), 64, [&](uint32_t b, uint32_t e, int) {
                   for (uint32_t i = b; i < e; ++i) {
                     if (p.kind[i] != ParticleKind::Free) continue;
                     const float u = rng.uniform(ctx.frame, i) - 0.5f;
                     p.vz[i] = 1e-3f * u * tool_z;
                     p.z[i] += p.vz[i] * static_cast<float>(ctx.dt_s);
                   }
                 });
               }});
  s.push_back({.name = "test_centroid",
               .phase = Phase::Metrics,
               .reads = {"capsule.particles"},
               .writes = {"test.probe"},
               .run = [&scene, capsule, &probe](const FrameContext&) {
                 const Particles& p = scene.world.at<Particles>(capsule);
                 const float sum = parallel_reduce_ordered(
                     0u, p.slots.size(), 64, 0.0f,
                     [&](uint32_t b, uint32_t e) {
                       float acc = 0;
                       for (uint32_t i = b; i < e; ++i) acc += p.z[i];
                       return acc;
                     },
                     [](float a, float b) { return a + b; });
                 probe.centroid_z.push_back(sum / static_cast<float>(p.slots.size()));
               }});
  return s;
}

struct Outcome {
  std::string hash;
  std::vector<double> centroid_z;
};

Outcome run_with_threads(int threads) {
  JitterProbe probe;
  SceneOptions o;
  o.threads = threads;
  o.cache_dir = cache_dir();
  o.extra_systems = [&probe](Scene& s) { return jitter_systems(s, probe); };
  auto scene = build_scene(small_scenario(), o);
  for (uint64_t f = 0; f < scene->scenario.frame_count(); ++f) step(*scene);
  return {state_hash(*scene), probe.centroid_z};
}

TEST(Determinism, SameStateHashForOneTwoAndFourThreads) {
  const Outcome one = run_with_threads(1);
  ASSERT_EQ(one.centroid_z.size(), 50u);
  const Outcome two = run_with_threads(2);
  const Outcome four = run_with_threads(4);
  EXPECT_EQ(one.hash, two.hash);
  EXPECT_EQ(one.hash, four.hash);
  EXPECT_EQ(one.centroid_z, two.centroid_z) << "ordered reduction must be bit-identical";
  EXPECT_EQ(one.centroid_z, four.centroid_z);
  // The probe really changes the state: a run without it hashes differently.
  SceneOptions plain;
  plain.cache_dir = cache_dir();
  auto scene = build_scene(small_scenario(), plain);
  for (uint64_t f = 0; f < scene->scenario.frame_count(); ++f) step(*scene);
  EXPECT_NE(state_hash(*scene), one.hash);
}

TEST(Scene, DrillLoadsOnlyTheBodiesItNeeds) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  auto rhexis = build_scene(small_scenario(Drill::Capsulorhexis), o);
  EXPECT_TRUE(rhexis->body(BodyPart::Capsule).has_value());
  EXPECT_TRUE(rhexis->body(BodyPart::LensSurface).has_value());
  EXPECT_FALSE(rhexis->body(BodyPart::Lens).has_value()) << "no tetrahedral lens until sculpting";
  auto incision = build_scene(small_scenario(Drill::CornealIncision), o);
  EXPECT_FALSE(incision->body(BodyPart::Capsule).has_value());
  EXPECT_TRUE(incision->body(BodyPart::LensSurface).has_value()) << "drawn: the red reflex";
  EXPECT_FALSE(incision->body(BodyPart::Lens).has_value());
  EXPECT_TRUE(incision->body(BodyPart::Cornea).has_value());
  auto sculpt = build_scene(small_scenario(Drill::PhacoSculpting), o);
  EXPECT_TRUE(sculpt->body(BodyPart::Lens).has_value());
}

TEST(Scene, ToolsFollowTheirTracks) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  auto scene = build_scene(small_scenario(), o);
  for (int f = 0; f < 25; ++f) step(*scene);  // t = 0.25 s
  const ToolState& cystotome = scene->world.at<ToolState>(scene->tools[1]);
  EXPECT_NEAR(cystotome.pos.z(), 1.9, 1e-9);
  const ToolState& forceps = scene->world.at<ToolState>(scene->tools[0]);
  EXPECT_NEAR(forceps.grip, 0.5, 1e-9);
  EXPECT_NEAR(forceps.pos.z(), 2.75, 1e-9);
}

TEST(Scene, CapsuleRimIsAnchoredAndInteriorHasMass) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  auto scene = build_scene(small_scenario(), o);
  const Particles& p = scene->world.at<Particles>(*scene->body(BodyPart::Capsule));
  size_t anchored = 0, free = 0;
  for (uint32_t i = 0; i < p.slots.size(); ++i) {
    if (p.kind[i] == ParticleKind::Anchored) {
      ++anchored;
      EXPECT_EQ(p.inv_mass[i], 0.0f);
      EXPECT_GT(std::hypot(p.x[i], p.y[i]), 4.0f) << "only the rim is held";
    } else {
      ++free;
      EXPECT_GT(p.inv_mass[i], 0.0f);
    }
  }
  EXPECT_GT(anchored, 0u);
  EXPECT_GT(free, anchored);
}

TEST(Scene, BadOverrideNamesScenarioAndKey) {
  Scenario s = small_scenario();
  s.eye.overrides["capsule.stiffnes_kpa"] = 3.0;
  SceneOptions o;
  o.cache_dir = cache_dir();
  try {
    build_scene(s, o);
    FAIL() << "unknown override accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("small.json: eye.overrides[\"capsule.stiffnes_kpa\"]"),
              std::string::npos)
        << e.what();
  }
  // Out of its physical range: refused before any mesh, naming the field and the range.
  Scenario far = small_scenario();
  far.eye.overrides["capsule.youngs_modulus_kpa"] = 1e300;
  const std::string msg = test::input_error_of([&] { check_scene_inputs(far); });
  EXPECT_NE(msg.find("small.json: eye.overrides[\"capsule.youngs_modulus_kpa\"]: expected a number "
                     "in 100..20000"),
            std::string::npos)
      << msg;
  far.eye.overrides["capsule.youngs_modulus_kpa"] = 20000;  // the edge
  EXPECT_NO_THROW(check_scene_inputs(far));
}

// The forceps close over the capsule, lift the grasped point 0.3 mm and move it sideways: the
// capsule follows locally, the active set stays a small part of the mesh, nothing diverges.
Scenario grasp_scenario(const std::string& integrator) {
  const std::string text = R"({
    "drill": "capsulorhexis", "eye": { "level": 1 }, "dt_s": 0.008333333333333333, "seed": 3, "duration_s": 1.0,
    "methods": { "capsule.integrator": ")" +
                           integrator + R"(" },
    "hands": { "left": { "tool": "forceps", "track": [
      { "t": 0.0, "pos": [1.0, 0.0, 1.72], "grip": 0.0 },
      { "t": 0.1, "pos": [1.0, 0.0, 1.72], "grip": 1.0 },
      { "t": 0.6, "pos": [1.2, 0.3, 2.02], "grip": 1.0 },
      { "t": 1.0, "pos": [1.2, 0.3, 2.02], "grip": 1.0 } ] } } })";
  return parse_scenario(text, "grasp.json", ".");
}

TEST(CapsulePhysics, GraspLiftsTheCapsuleLocally) {
  for (const std::string integrator :
       {"implicit_euler", "implicit_predictor", "semi_implicit_001"}) {
    SCOPED_TRACE(integrator);
    SceneOptions o;
    o.cache_dir = cache_dir();
    auto scene = build_scene(grasp_scenario(integrator), o);
    const Entity capsule = *scene->body(BodyPart::Capsule);
    const Particles before = scene->world.at<Particles>(capsule);
    for (uint64_t f = 0; f < scene->scenario.frame_count(); ++f) step(*scene);
    const Particles& p = scene->world.at<Particles>(capsule);
    const CapsuleStats& cp = scene->world.at<CapsuleStats>(capsule);
    const CapsuleSolver& solver = scene->world.at<CapsuleSolver>(capsule);
    EXPECT_EQ(cp.grasps, 1u);
    const ToolGrasp& g = scene->world.at<ToolGrasp>(scene->tools[0]);
    ASSERT_TRUE(g.capsule.holding());
    EXPECT_NEAR(p.z[g.capsule.particle], 2.02f, 1e-5f) << "the held point is at the forceps tip";
    uint32_t lifted_neighbours = 0;
    for (uint32_t i = 0; i < p.slots.size(); ++i) {
      ASSERT_TRUE(std::isfinite(p.x[i]) && std::isfinite(p.y[i]) && std::isfinite(p.z[i]));
      const float dz = p.z[i] - before.z[i];
      const float r = std::hypot(before.x[i] - 1.0f, before.y[i]);
      if (r > 0.05f && r < 0.3f && dz > 0.02f) ++lifted_neighbours;
    }
    EXPECT_GT(lifted_neighbours, 3u) << "the membrane around the grasp rises with it";
    EXPECT_GT(cp.active_particle_max, 20u);
    EXPECT_LT(cp.active_particle_max, p.slots.size() / 2)
        << "cost stays local: the active set is a small part";
    EXPECT_EQ(solver.state.status.fallbacks, 0u);
  }
}

TEST(CapsulePhysics, BadMethodsAreRejectedByName) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  Scenario s = grasp_scenario("runge_kutta");
  try {
    build_scene(s, o);
    FAIL() << "unknown integrator accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "grasp.json: methods[\"capsule.integrator\"]: unknown choice 'runge_kutta'"),
              std::string::npos)
        << e.what();
  }
  s = grasp_scenario("xpbd");
  s.methods["lens.integrator"] = "xpbd";
  EXPECT_THROW(build_scene(s, o), InputError);
  s = grasp_scenario("xpbd");
  s.drill = Drill::CornealIncision;
  EXPECT_THROW(build_scene(s, o), InputError) << "the incision scene has no capsule";
}

// Method values are checked before any mesh (issue 18: what validate accepts, run runs): each
// key's choices from the one table, the CG tolerance a number in (0, 1), lens sculpting settings
// only with the tetrahedral lens, ports only where the drill file gives their sites.
TEST(CapsulePhysics, BadMethodValuesAreRefusedBeforeAnyMesh) {
  const auto refused = [](Scenario s, const std::string& key, const std::string& value,
                          const std::string& expected) {
    s.methods[key] = value;
    const std::string msg = test::input_error_of([&] { check_scene_inputs(s); });
    EXPECT_NE(msg.find("methods[\"" + key + "\"]: " + expected), std::string::npos)
        << key << " = " << value << ": " << msg;
  };
  const Scenario rhexis = grasp_scenario("xpbd");
  refused(rhexis, "capsule.integrator", "runge_kutta", "unknown choice 'runge_kutta'");
  refused(rhexis, "capsule.preconditioner", "multigrid", "unknown choice 'multigrid'");
  refused(rhexis, "capsule.cg_tolerance", "1.5", "expected a number in (0, 1)");
  refused(rhexis, "capsule.cg_tolerance", "tight", "expected a number in (0, 1)");
  refused(rhexis, "tools.ports", "always", "unknown choice 'always'");
  Scenario ok = rhexis;
  ok.methods["capsule.cg_tolerance"] = "1e-8";
  ok.methods["capsule.preconditioner"] = "two_level";
  EXPECT_NO_THROW(check_scene_inputs(ok));
  // Every choice the table lists is one the scene takes (the table and the systems agree).
  for (const MethodSetting& m : method_settings()) {
    if (m.key.rfind("capsule.", 0) != 0) continue;
    for (std::string_view c : m.choices) {
      Scenario each = rhexis;
      each.methods[std::string(m.key)] = std::string(c);
      EXPECT_NO_THROW(check_scene_inputs(each)) << m.key << " = " << c;
    }
  }
}

TEST(Run, ReportHasEveryRequiredField) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  o.threads = 2;
  const RunReport r = run_scenario(small_scenario(), o);
  const nlohmann::json j = to_json(r);
  for (const char* key : {"drill", "sim_time_s", "frames", "threads", "systems", "peak_memory_mb",
                          "elements", "metrics", "events", "state_hash"}) {
    EXPECT_TRUE(j.contains(key)) << key;
  }
  EXPECT_EQ(j["drill"], "capsulorhexis");
  EXPECT_EQ(j["frames"], 50);
  EXPECT_NEAR(j["sim_time_s"].get<double>(), 0.5, 1e-12);
  EXPECT_EQ(j["threads"], 2);
  EXPECT_TRUE(j["systems"].contains("move_tools"));
  EXPECT_TRUE(j["systems"]["move_tools"].contains("p50_ms"));
  EXPECT_TRUE(j["systems"]["move_tools"].contains("p99_ms"));
  EXPECT_GT(j["elements"]["capsule.particles"].get<uint64_t>(), 500u);
  EXPECT_GT(j["peak_memory_mb"].get<double>(), 1.0);
  EXPECT_EQ(j["state_hash"].get<std::string>().size(), 16u);
  EXPECT_EQ(j["physics"]["capsule"]["integrator"], "implicit_euler");
}

}  // namespace
}  // namespace phaco
