// The capsule's physics in a scene (procedures/scene/capsule_physics.cpp): the implicit solve's
// preconditioner is chosen by `methods`, reported in the summary, and every choice gives the same
// state hash on one and two threads, with the threaded product and preconditioners engaged.
#include <gtest/gtest.h>

#include <filesystem>

#include "engine/core/error.hpp"
#include "procedures/scene/capsule_physics.hpp"
#include "procedures/scene/run.hpp"

namespace phaco {
namespace {

std::filesystem::path cache_dir() {
  const char* env = std::getenv("PHACO_CACHE_DIR");
  return env ? std::filesystem::path(env)
             : std::filesystem::temp_directory_path() / "phaco-test-cache";
}

// The forceps close over the capsule and lift the grasped point: the active set grows around it.
Scenario grasp_scenario(const std::string& preconditioner) {
  const std::string text = R"({
    "drill": "capsulorhexis", "eye": { "level": 1 }, "dt_s": 0.008333333333333333, "seed": 3, "duration_s": 0.4,
    "methods": { "capsule.preconditioner": ")" +
                           preconditioner + R"(" },
    "hands": { "left": { "tool": "forceps", "track": [
      { "t": 0.0, "pos": [1.0, 0.0, 1.72], "grip": 0.0 },
      { "t": 0.1, "pos": [1.0, 0.0, 1.72], "grip": 1.0 },
      { "t": 0.4, "pos": [1.2, 0.3, 2.02], "grip": 1.0 } ] } } })";
  return parse_scenario(text, "grasp.json", ".");
}

struct Outcome {
  std::string hash;
  nlohmann::json summary;
};

Outcome run(const std::string& preconditioner, int threads) {
  SceneOptions o;
  o.threads = threads;
  o.cache_dir = cache_dir();
  auto scene = build_scene(grasp_scenario(preconditioner), o);
  // Thread every row loop of the step, whatever the active set's size, so that two threads really
  // split the assembly, the product, the preconditioners and the row-chunked CG.
  deform::ImplicitSettings& settings =
      scene->world.at<CapsuleSolver>(*scene->body(BodyPart::Capsule)).state.implicit.settings;
  settings.parallel_min_unknowns = 0;
  settings.parallel_grain_unknowns = 8;
  settings.cg_team_min_rows = 0;  // a team of two for the assembly and the row-chunked CG
  settings.team_policy = deform::TeamPolicy::Always;
  settings.parallel_grain_rows = 8;
  settings.parallel_grain_springs = 16;
  for (uint64_t f = 0; f < scene->scenario.frame_count(); ++f) step(*scene);
  return {state_hash(*scene), capsule_physics_summary(*scene)};
}

TEST(CapsulePhysics, EveryPreconditionerGivesTheSameStateHashOnOneAndTwoThreads) {
  for (const std::string p :
       {"jacobi", "block_jacobi", "incomplete_cholesky", "two_level", "deflation", "balancing"}) {
    SCOPED_TRACE(p);
    const Outcome one = run(p, 1), two = run(p, 2);
    EXPECT_EQ(one.hash, two.hash);
    EXPECT_EQ(one.summary["preconditioner"], p);
    EXPECT_GT(one.summary["cg_iterations_total"].get<uint64_t>(), 0u);
    EXPECT_GT(one.summary["cg_iterations_per_step_mean"].get<double>(), 0.0);
    EXPECT_EQ(one.summary["divergences"], 0u);
    // The row-chunked CGs (deflation's too) really ran on the team of two, and the hash held.
    EXPECT_EQ(one.summary["team_steps"], 0u);
    if (p == "jacobi" || p == "block_jacobi" || p == "deflation")
      EXPECT_GT(two.summary["team_steps"].get<uint64_t>(), 0u);
  }
}

TEST(CapsulePhysics, UnknownPreconditionerIsRejectedByName) {
  SceneOptions o;
  o.cache_dir = cache_dir();
  try {
    build_scene(grasp_scenario("multigrid"), o);
    FAIL() << "unknown preconditioner accepted";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(
                  "methods[\"capsule.preconditioner\"]: unknown choice 'multigrid'"),
              std::string::npos)
        << e.what();
  }
}

}  // namespace
}  // namespace phaco
