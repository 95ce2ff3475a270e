#pragma once
// What the divergence guard measures and keeps: the energy of the particles and springs in play,
// a copy of their state to roll a failed step back to, and the clean-up of non-finite input.
//
// Energy rule (deform.hpp applies it). With the tools holding still during a step (scripted
// particles are moved between steps, never inside one), every force but damping and the
// environment's correction is conservative, so
//     H = Σ ½·m̃·v² + Σ U_spring + Σ ½·k_glue·|x − x_glue|² − Σ m·g·x − Σ F_load·x
// can only fall over an exact step. A step counts as diverged when
//     H_after − H_before > growth·(S_before + |V_after − V_before|) + floor,
// S = kinetic + elastic + glue energy (≥ 0) and V the potential of gravity and loads: the energy
// gained must stay a bounded fraction of the energy present and of the work the loads did. A
// stable method's error stays below that (symplectic Euler's energy error is O(ω·dt)); a mode
// that grows by a factor above 1 + growth per step does not. NaN, infinity and speeds above
// Dynamics::max_speed_mm_s are caught by the integrators themselves (Motion::bad).
//
// Reads: particles, springs, dynamics, glue, loads. Writes: particles (restore, sanitize only).
#include <cstdint>
#include <vector>

#include "systems/deform/membrane.hpp"

namespace phaco::deform {

struct Energy {
  double kinetic = 0.0;  // µJ = mN·mm
  double elastic = 0.0;  // springs in play
  double glue = 0.0;
  double potential = 0.0;  // gravity and loads, relative to the origin

  double stored() const { return kinetic + elastic + glue; }
  double total() const { return stored() + potential; }
};

// Sums in a fixed order (bit-identical for any thread count).
Energy measure_energy(const Membrane& m);

struct EnergyBound {
  double growth = 1.0;      // allowed gain per step as a fraction of S_before + |ΔV|
  double floor_uj = 1e-12;  // absolute slack, µJ, for a body at rest
};

bool energy_diverged(const Energy& before, const Energy& after, const EnergyBound& bound);

// x and v per particle, indexed by particle. The first save copies every particle (and is the
// only allocation); later saves and restores touch the particles in play only, so the other
// entries keep the last state seen for them.
struct Snapshot {
  std::vector<float> x, y, z, vx, vy, vz;
};

// Replaces a non-finite position or velocity of every particle the step reads (those in play and
// the sleeping ends of active springs): the position by the snapshot's if that is finite, else the
// glue rest position, else the origin; the velocity by zero. Then saves the particles in play into
// the snapshot, the state a failed step is rolled back to. One pass; returns how many particles
// were repaired.
uint32_t sanitize_and_save(Membrane& m, Snapshot& snap);

// Puts the particles in play back to the snapshot.
void restore_state(Membrane& m, const Snapshot& snap);

// Sets the velocity of every free particle in play to zero (the last resort of the recovery:
// hold the shape where the last good step left it).
void hold_still(Membrane& m);

}  // namespace phaco::deform
