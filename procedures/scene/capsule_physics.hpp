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
//   capsule.preconditioner  jacobi | block_jacobi | incomplete_cholesky | two_level: implicit
//                        Euler's CG preconditioner (default block_jacobi; systems/deform/implicit_solver.hpp)
//   capsule.cutting      on | off, capsule.tear_rule flap_force | most_stressed_spring
//                        (procedures/scene/capsule_cutting.hpp)
#include <initializer_list>
#include <string>
#include <string_view>

#include <nlohmann/json.hpp>

#include "components/dynamics.hpp"
#include "components/springs.hpp"
#include "engine/schedule/system.hpp"
#include "systems/active_nodes/active_nodes.hpp"
#include "systems/deform/deform.hpp"
#include "systems/grasp/grasp.hpp"
#include "systems/springs/springs.hpp"

namespace phaco {

struct Scene;

struct CapsulePhysics {
  springs::SpringMaterial material;  // what the springs were built with (cutting re-springs with it)
  Springs springs;
  SpringBlocks blocks;
  Forces forces;
  Dynamics dynamics;
  Glue glue;
  deform::Environment environment;
  deform::DeformState state;
  SpringGraph graph;
  active_nodes::ActiveSet active;
  bool use_active_set = true;
  uint32_t active_hops = 8;
  double wake_motion_mm = 1e-3;  // a neighbour moving more than this in a step wakes a sleeper
  double wake_force_mn = 1e-2;   // so does an unbalanced force above this
  grasp::GraspSettings grasp;
  std::vector<uint32_t> seeds;  // this frame's active-set seeds (scratch)

  // Over the run, for the report.
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
// the allowed choices otherwise.
std::string method_choice(const Scene& scene, const std::string& key, const std::string& fallback,
                          std::initializer_list<std::string_view> allowed);

// Known `methods` keys for the capsule; every other "capsule.*" key is rejected by the scene.
bool is_capsule_method(const std::string& key);

// Builds the capsule's physics from the scene's parameters and methods (InputError naming the
// scenario's `methods` field on a bad choice) and adds it to the capsule entity.
void add_capsule_physics(Scene& scene);

// The frame's system for it: reads tools.pose, writes capsule.particles.
SystemDesc capsule_dynamics_system(Scene& scene);

// Integrator, counts and averages for the run report.
nlohmann::json capsule_physics_summary(const Scene& scene);

}  // namespace phaco
