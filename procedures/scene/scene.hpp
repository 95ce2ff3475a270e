#pragma once
// A scene: the World a drill needs (bodies of the eye, tools with their tracks), its per-frame
// task graph and the executor that runs it. Built once from a scenario; stepped at the fixed dt.
//
// Which bodies a drill loads is its drill file's "scene.bodies" (data/drills; model no more than
// the scene needs, DESIGN.md §3):
//   corneal_incision: cornea, iris, globe, lens_surface (drawn: the red reflex; no lens physics)
//   capsulorhexis:    cornea, capsule, iris, lens_surface
//   phaco_sculpting:  cornea, capsule, iris, lens (tetrahedra)
//   nucleus_removal:  cornea, capsule, iris, lens (simplex cells, grooved; lens_fragments.hpp)
#include <array>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "components/body.hpp"
#include "engine/ecs/command_buffer.hpp"
#include "engine/ecs/world.hpp"
#include "engine/io/drill_file.hpp"
#include "engine/io/scenario.hpp"
#include "engine/schedule/executor.hpp"
#include "engine/schedule/frame_graph.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "procedures/scene/carried_state.hpp"
#include "procedures/scene/haptic_port.hpp"
#include "procedures/scene/track_pivot.hpp"

namespace phaco {

struct Scene;

struct SceneOptions {
  int threads = 1;
  std::optional<std::filesystem::path> cache_dir;  // default: MeshCache::default_dir()
  // Extra systems (tests, tools): called once the bodies exist, before the graph is built.
  std::function<std::vector<SystemDesc>(Scene&)> extra_systems;
  // A haptic runtime (issue 6): device-driven hands take their pose from it, and the frame ends by
  // publishing the local haptic model to it. Null: every hand follows its track, nothing published.
  HapticPort* haptics = nullptr;
  // Whether the executor checks, while systems run, that they touch only what they declared and
  // never race (engine/schedule/executor.hpp). BuildDefault: on in debug builds.
  AccessCheck access_check = AccessCheck::BuildDefault;
  // How frames reach the threads (engine/schedule/executor.hpp); Auto unless a study compares.
  Dispatch dispatch = Dispatch::Auto;
  // A procedure's earlier steps (procedures/procedure): the eye as they left it, instead of the
  // drill's fresh eye. Null: the drill's own start state.
  const CarriedState* carried = nullptr;
};

struct Scene {
  Scenario scenario;
  DrillFile drill;                // its drill file (data/drills, docs/drills.md)
  DifficultySettings difficulty;  // the level's settings with the scenario's over them
  eye::EyeParams params;          // eye file, then difficulty, then the scenario's overrides
  eye::Resolution resolution;
  World world;
  std::vector<Entity> bodies;  // in creation order
  std::vector<Entity> tools;
  CommandQueues commands;
  std::unique_ptr<FrameGraph> graph;
  std::unique_ptr<Executor> executor;
  uint64_t frame = 0;
  double time_s = 0;
  double mesh_load_s = 0;         // wall time to load or build the meshes
  HapticPort* haptics = nullptr;  // from SceneOptions
  CarriedState carried;           // from SceneOptions (empty: the drill's start state)
  // Per hand (indexed as Hand): its track moved from the drill's default main port into the
  // carried one (procedures/scene/track_pivot); none on a fresh eye.
  std::array<std::optional<TrackPivot>, 2> track_pivots;

  std::optional<Entity> body(BodyPart part) const;
};

// The scenario's drill file: its "drill_file", else eye::data_dir()/drills/<drill>.json. Throws
// InputError naming the scenario and the file, also when the file is of another drill.
DrillFile load_drill_for(const Scenario& scenario);

// {"file", "title", "difficulty": level, "settings": {...}} for the run report.
nlohmann::json drill_setup_json(const Scene& scene);

// Throws InputError naming the scenario file and field for bad eye parameters or mesh files.
std::unique_ptr<Scene> build_scene(const Scenario& scenario, const SceneOptions& options);

// One fixed step: runs the frame graph once.
void step(Scene& scene);

// Hash of every body's elements and every tool's pose (bit-exact; equal for any thread count).
std::string state_hash(const Scene& scene);

// Element counts per kind, e.g. "capsule.particles", "lens.tets".
std::vector<std::pair<std::string, uint64_t>> element_counts(const Scene& scene);

}  // namespace phaco
