#pragma once
// The capsulorhexis scene's membrane physics: the anterior capsule as pre-stretched springs on its
// mesh, held on the lens by weak glue springs (seed 001), kept out of the lens and away from the
// cornea by the environment correction, grasped by the forceps, and integrated only on the active
// node set around what the tools hold (seed 003 §III.D) — so a frame costs what the tool touches.
//
// Settings come from the eye parameter file's `capsule` (material) and `capsule_model` (model)
// sections, and from the scenario's `methods`:
//   capsule.integrator   explicit_euler | symplectic_euler | semi_implicit_001 | implicit_euler |
//                        implicit_predictor | xpbd              (default implicit_euler)
//   capsule.spring_law   linear | quadratic                     (default linear)
//   capsule.stiffness    area_weighted | uniform                (default area_weighted)
//   capsule.pretension   cotangent | uniform_prestretch         (default cotangent: isotropic
//                        tension on any mesh, docs/membrane_accuracy.md)
//   capsule.active_set   on | off                               (default on)
//   capsule.preconditioner  jacobi | block_jacobi | incomplete_cholesky | two_level |
//                        deflation | balancing: implicit Euler's CG preconditioner (default
//                        block_jacobi; systems/deform/implicit_solver.hpp)
//   capsule.cutting      on | off, capsule.tear_rule flap_force | most_stressed_spring
//                        (procedures/scene/capsule_cutting.hpp)
#include <initializer_list>
#include <nlohmann/json.hpp>
#include <string>
#include <string_view>

#include "components/dynamics.hpp"
#include "components/springs.hpp"
#include "engine/schedule/system.hpp"
#include "systems/active_nodes/active_nodes.hpp"
#include "systems/deform/deform.hpp"
#include "systems/grasp/grasp.hpp"
#include "systems/springs/springs.hpp"

namespace phaco {

struct Scene;

// The capsule's physics is four components, each under its own access name, so the frame graph
// can overlap what does not conflict (Jolt keeps a soft body's shared settings apart from its
// runtime state in the same way):
//
//   capsule.springs   CapsuleSprings   shared structure that changes only with topology: written by
//                                      the build and the topology phase (capsule_cut), read by the
//                                      dynamics, the haptic model and the metrics
//   capsule.solver    CapsuleSolver    per-frame state of the integration: written only by
//                                      capsule_dynamics
//   capsule.settings  CapsuleSettings  material, dynamics, grasp and wake settings: read-only
//                                      after the build
//   capsule.stats     CapsuleStats     counters for the run report: written by capsule_dynamics

// capsule.springs. A cut or tear patches it (procedures/scene/capsule_cutting.hpp): new springs go
// to the blocks' tail, the graph's touched rows are patched, glue grows for new particles; a full
// re-plan happens only in a frame without topology change. `version` counts those changes so the
// solver can tell its cached structure is stale without the topology phase writing the solver.
struct CapsuleSprings {
  Springs springs;
  SpringBlocks blocks;
  SpringGraph graph;
  Glue glue;             // per particle: the point on the lens its glue spring pulls to, mm
  uint64_t version = 0;  // +1 whenever springs, blocks or graph change after the build
  // Edges built with the uniform pre-stretch because their cotangent tension needs a rest length
  // below half the edge (systems/springs build_springs; a high pre-stretch on a coarse mesh).
  uint32_t clamped_pretension = 0;
};

// capsule.solver.
struct CapsuleSolver {
  Forces forces;
  deform::DeformState state;
  active_nodes::ActiveSet active;
  std::vector<uint32_t> seeds;   // this frame's active-set seeds (scratch)
  uint64_t springs_version = 0;  // the CapsuleSprings::version the solver's caches were built for
};

// capsule.settings.
struct CapsuleSettings {
  springs::SpringMaterial
      material;  // what the springs were built with (cutting re-springs with it)
  Dynamics dynamics;
  deform::Environment environment;
  bool use_active_set = true;
  uint32_t active_hops = 8;
  double wake_motion_mm = 1e-3;  // a neighbour moving more than this in a step wakes a sleeper
  double wake_force_mn = 1e-2;   // so does an unbalanced force above this
  grasp::GraspSettings grasp;
};

// capsule.stats: over the run, for the report.
struct CapsuleStats {
  uint64_t frames_stepped = 0;
  uint64_t active_particle_sum = 0;
  uint32_t active_particle_max = 0;
  uint64_t grasps = 0, releases = 0, missed_grasps = 0;
};

// Per forceps: what it holds of the capsule.
struct ToolGrasp {
  grasp::GraspState capsule;
};

// The scenario's choice for a `methods` key, `fallback` if absent; InputError naming the key and
// its choices (procedures/scene/method_settings.hpp, the one table of them) otherwise.
std::string method_choice(const Scene& scene, const std::string& key, const std::string& fallback);

// Known `methods` keys for the capsule; every other "capsule.*" key is rejected by the scene.
bool is_capsule_method(const std::string& key);

// Builds the capsule's physics from the scene's parameters and methods (InputError naming the
// scenario's `methods` field on a bad choice) and adds its four components to the capsule entity.
void add_capsule_physics(Scene& scene);

// The frame's system for it. Reads: tools.pose, capsule.springs, capsule.settings,
// capsule.triangles (debug builds check the membrane every frame), capsule.cutting (the cut's
// fresh lips seed the active set). Writes: capsule.particles, capsule.solver, capsule.stats,
// tools.grasp.
SystemDesc capsule_dynamics_system(Scene& scene);

// Integrator, counts and averages for the run report.
nlohmann::json capsule_physics_summary(const Scene& scene);

}  // namespace phaco
