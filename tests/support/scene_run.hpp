#pragma once
// Running a scenario in a scene for a test: the mesh cache the tests share, and a run to the end.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <filesystem>
#include <memory>

#include "procedures/scene/scene.hpp"

namespace phaco::test {

// PHACO_CACHE_DIR if set, else a cache under the system's temporary directory.
inline std::filesystem::path scene_cache_dir() {
  const char* env = std::getenv("PHACO_CACHE_DIR");
  return env ? std::filesystem::path(env)
             : std::filesystem::temp_directory_path() / "phaco-test-cache";
}

// Scene options with that cache, the rest default.
inline SceneOptions scene_options() {
  SceneOptions o;
  o.cache_dir = scene_cache_dir();
  return o;
}

inline Scenario repo_scenario(const char* name) {
  return load_scenario(std::filesystem::path(PHACO_SOURCE_DIR) / "data/scenarios" / name);
}

// Builds the scene and steps it for the scenario's whole duration.
inline std::unique_ptr<Scene> run_to_end(const Scenario& s, int threads) {
  SceneOptions o;
  o.threads = threads;
  o.cache_dir = scene_cache_dir();
  auto scene = build_scene(s, o);
  const auto frames = static_cast<uint64_t>(std::llround(s.duration_s / s.dt_s));
  for (uint64_t f = 0; f < frames; ++f) step(*scene);
  return scene;
}

// The sculpting probe enters through its port, then plunges with ultrasound on through the whole
// lens to 0.3 mm beyond its posterior pole (a posterior capsule rupture), over 2 s.
inline void plunge_through_posterior_capsule(Scenario& s, double posterior_pole_mm) {
  const Quat q = Quat(0.719345, -0.075527, 0.690535, 0.0).normalized();
  const double z = -(posterior_pole_mm + 0.3);
  for (HandTrack& h : s.hands) {
    if (h.tool != ToolKind::PhacoProbe) continue;
    h.track = {{0.0, Vec3(5.26, 0.0, 2.35), q, 0, 0},
               {0.5, Vec3(2.3, -0.35, 2.3), q, 0, 1},
               {1.5, Vec3(0.3, 0.0, z), q, 0, 3},
               {2.0, Vec3(0.3, 0.0, z), q, 0, 3}};
  }
  s.duration_s = 2.0;
}

}  // namespace phaco::test
