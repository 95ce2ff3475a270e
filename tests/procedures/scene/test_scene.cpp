#include <gtest/gtest.h>

#include <filesystem>

#include "components/particles.hpp"
#include "components/tool.hpp"
#include "engine/core/error.hpp"
#include "engine/core/rng.hpp"
#include "engine/schedule/parallel.hpp"
#include "procedures/scene/run.hpp"

namespace phaco {
namespace {

std::filesystem::path cache_dir() {
  const char* env = std::getenv("PHACO_CACHE_DIR");
  return env ? std::filesystem::path(env) : std::filesystem::temp_directory_path() / "phaco-test-cache";
}

Scenario small_scenario(Drill drill = Drill::Capsulorhexis) {
  const std::string text = R"({
    "drill": ")" + std::string(to_string(drill)) + R"(",
    "eye": { "level": 0 },
    "dt_s": 0.01, "seed": 11, "duration_s": 0.5,
    "hands": {
      "left":  { "tool": "forceps", "track": [
        { "t": 0.0, "pos": [-1.0, 0.0, 3.5], "quat": [1, 0, 0, 0], "grip": 0.0 },
        { "t": 0.5, "pos": [-1.0, 0.5, 2.0], "quat": [0.7071, 0.7071, 0, 0], "grip": 1.0 } ] },
      "right": { "tool": "cystotome", "track": [
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
  s.push_back({.name = "test_jitter", .phase = Phase::Dynamics, .reads = {"tools.pose"},
               .writes = {"capsule.particles"}, .run = [&scene, capsule, seed](const FrameContext& ctx) {
                 Particles& p = scene.world.at<Particles>(capsule);
                 const CounterRng rng(seed, 3);
                 const float tool_z = static_cast<float>(scene.world.at<ToolState>(scene.tools[1]).pos.z());
                 parallel_for(0, p.slots.size(), 64, [&](uint32_t b, uint32_t e, int) {
                   for (uint32_t i = b; i < e; ++i) {
                     if (p.kind[i] != ParticleKind::Free) continue;
                     const float u = rng.uniform(ctx.frame, i) - 0.5f;
                     p.vz[i] = 1e-3f * u * tool_z;
                     p.z[i] += p.vz[i] * static_cast<float>(ctx.dt_s);
                   }
                 });
               }});
  s.push_back({.name = "test_centroid", .phase = Phase::Metrics, .reads = {"capsule.particles"},
               .writes = {"test.probe"}, .run = [&scene, capsule, &probe](const FrameContext&) {
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
  EXPECT_FALSE(incision->body(BodyPart::LensSurface).has_value());
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
    EXPECT_NE(std::string(e.what()).find("small.json: eye.overrides.capsule.stiffnes_kpa"), std::string::npos)
        << e.what();
  }
}

TEST(Run, ReportHasEveryRequiredField) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  o.threads = 2;
  const RunReport r = run_scenario(small_scenario(), o);
  const nlohmann::json j = to_json(r);
  for (const char* key : {"drill", "sim_time_s", "frames", "threads", "systems", "peak_memory_mb", "elements",
                          "metrics", "events", "state_hash"}) {
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
}

}  // namespace
}  // namespace phaco
