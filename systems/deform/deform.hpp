#pragma once
// One dynamics step of a deformable membrane (capsule, cornea): the integrator the body's
// Dynamics names, its substeps, seed 001's environment correction after every substep, and a
// divergence guard that never lets NaN, infinity or a runaway state out.
//
//   step(m, dt, state)
//     1. clean the input: non-finite loads are ignored (compute_forces), non-finite particle
//        states are repaired from the last good state (guard.hpp); save the state in play
//     2. run `substeps_in_use` substeps of `in_use`, each followed by apply_environment
//     3. diverged? — a particle non-finite or faster than Dynamics::max_speed_mm_s (checked after
//        every substep, so a hopeless attempt stops early), or the energy rule of guard.hpp
//     4. recover: restore the saved state and retry with doubled substeps up to
//        GuardSettings::max_substeps; then switch to GuardSettings::fallback (implicit Euler,
//        stable at any dt) from one substep, doubling again if even that fails; as a last resort
//        keep the restored positions and stop the motion (hold_still)
//
// Recovery sticks: the substeps and integrator that worked are kept in DynamicsStatus and used by
// the next steps, so a body that needs help pays for the failed attempts once, not every frame.
// They are reset when the body's Dynamics (integrator or substeps) changes, or, if
// GuardSettings::probe_after_steps > 0, after that many clean steps (then the configured method
// is tried again).
//
// Integrators (equations in explicit.hpp, xpbd.hpp, implicit.hpp; docs/dynamics.md):
// explicit_euler, symplectic_euler, semi_implicit_001 (seed 001 §3.4), implicit_euler (Eigen CG),
// implicit_predictor (seed 004), xpbd. All run over the active node set when Membrane::active is
// set (seed 003 §D); the rest of the body sleeps.
//
// Reads: springs, blocks, dynamics, glue, environment, active set, loads. Writes: particles (x, v
// of free particles in play), forces, state.
#include <cstdint>
#include <vector>

#include "components/dynamics.hpp"
#include "systems/deform/environment.hpp"
#include "systems/deform/explicit.hpp"
#include "systems/deform/forces.hpp"
#include "systems/deform/guard.hpp"
#include "systems/deform/implicit.hpp"
#include "systems/deform/membrane.hpp"
#include "systems/deform/xpbd.hpp"

namespace phaco::deform {

struct GuardSettings {
  bool check_energy = true;  // two energy passes per step; speed and NaN checks are always on
  EnergyBound energy;
  uint16_t max_substeps = 64;
  Integrator fallback = Integrator::ImplicitEuler;
  uint32_t probe_after_steps = 0;  // 0: a recovery sticks until the Dynamics settings change
};

// Everything a body's stepping carries from one step to the next. Grows on the first step (and
// when the particle or spring count changes); later steps do not allocate.
struct DeformState {
  DynamicsStatus status;
  GuardSettings guard;
  ImplicitCache implicit;
  XpbdScratch xpbd;
  std::vector<float> axial_stiffness;  // semi_implicit_001 scratch, mN/mm per particle
  Snapshot snapshot;                   // the state before the current step
  uint64_t rejected_loads = 0;         // non-finite loads ignored, over the run
  uint64_t repaired_particles = 0;     // non-finite particle states repaired, over the run
  uint64_t holds = 0;                  // steps that ended in hold_still

  // The Dynamics the recovery state belongs to.
  bool configured = false;
  Integrator configured_integrator = Integrator::ImplicitEuler;
  uint16_t configured_substeps = 1;
  uint64_t clean_steps = 0;  // since the last divergence
};

struct StepReport {
  Integrator integrator = Integrator::ImplicitEuler;  // what finally ran
  uint16_t substeps = 1;
  uint32_t attempts = 0;   // 1 when the first try passed
  bool diverged = false;   // at least one attempt was rejected
  bool fell_back = false;  // the fallback integrator ran
  bool held = false;       // every attempt failed; motion stopped
  uint32_t rejected_loads = 0;
  uint32_t repaired_particles = 0;
  uint32_t environment_corrections = 0;  // summed over the substeps of the accepted attempt
  float max_speed_mm_s = 0.0f;
  Energy energy_before, energy_after;  // zero unless GuardSettings::check_energy
};

StepReport step(Membrane& m, double dt_s, DeformState& state);

// One unguarded step of `integrator` without the environment correction (stability probes,
// benchmarks). Motion::bad counts particles that came out non-finite or too fast.
Motion integrate_once(Membrane& m, double dt_s, Integrator integrator, DeformState& state);

// The Motion figures of the particles in play (for integrators that do not report them).
Motion observe_motion(const Membrane& m);

}  // namespace phaco::deform
