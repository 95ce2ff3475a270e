#pragma once
// Forces on the particles of a membrane, the sum every deform integrator starts from.
//
//   f_i = Σ_springs F_s                      seed 000 §5.1 (quadratic) / seeds 001, 003 §E (Hooke)
//       + m_i·g                              gravity (seed 001 §3.4)
//       − m̃_i·damping·v_i − m̃_i·viscosity·v_i   seed 003 §E: f_d = −k_d·v, f_v = −k_v·v
//       − k_glue·(x_i − x_glue,i)            seed 001: weak positional springs to the lens
//       + external point loads               tools, tests
//
// m_i is the particle's true mass and m̃_i = m_i·mass_scale its effective (inertial) mass. Mass
// scaling is a numerical device for explicit steps, so it changes inertia only: the weight stays
// m·g (a static equilibrium does not move when the mass is scaled), and damping and viscosity are
// rates in 1/s, applied to the inertia they act on, so a decay time stays what was set.
//
// Forces are zeroed and summed on the particles in play (Membrane::active, or all), and, when the
// set is restricted, also on the sleeping ends of active springs: the force a sleeping neighbour
// receives is what wakes it. Anchored and scripted particles get forces too (the reaction a tool
// feels); the integrators never move them.
//
// Reads: particles, springs, blocks, dynamics, glue, loads. Writes: forces.
#include <cstdint>

#include "systems/deform/membrane.hpp"

namespace phaco::deform {

// Which terms to sum; XPBD treats springs and glue as constraints and damping as a velocity
// filter, so it asks for the others only.
struct ForceTerms {
  bool springs = true;
  bool damping = true;  // damping and viscosity
  bool glue = true;
};

// Returns the number of external loads ignored because a component was not finite (or the
// particle index was out of range). Deterministic for any thread count.
uint32_t compute_forces(Membrane& m, ForceTerms terms = {});

// The restricted spring pass alone: adds the force of every spring in `springs_in_play`, in list
// order, to both its ends. Exposed for the active-set code paths of the other deform passes.
void add_spring_forces_listed(const Membrane& m, std::span<const uint32_t> springs_in_play,
                              Forces& forces);

}  // namespace phaco::deform
