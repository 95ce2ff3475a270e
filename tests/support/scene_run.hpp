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

}  // namespace phaco::test
