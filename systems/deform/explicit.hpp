#pragma once
// Explicit and diagonally implicit mass-spring integrators over the particles in play
// (Membrane::active, or all). Each computes the forces (compute_forces) at the current state,
// then moves the free particles; anchored and scripted ones stay where they are. a = f/m̃ with
// m̃ = m·mass_scale (forces.hpp says what mass scaling changes).
//
//   explicit_euler       x⁺ = x + dt·v,   v⁺ = v + dt·a(x, v)
//   symplectic_euler     v⁺ = v + dt·a(x, v),   x⁺ = x + dt·v⁺
//       one spring-mass: stable iff ω·dt < 2 (ω² = k/m); explicit Euler's energy grows by
//       (1 + ω²dt²) every step, so it is unstable at every dt unless damped (c > ω²·dt).
//   semi_implicit_001    seed 001 §3.4: "the velocity is computed using an implicit method and has
//       a feedback on the position which is computed explicitly". Backward Euler for the velocity,
//       linearised and kept to the per-particle diagonal:
//           (1 + dt·c + dt²·κ_i/m̃_i)·v⁺ = (1 + dt·c)·v + dt·f_i/m̃_i,   x⁺ = x + dt·v⁺
//       with c = damping + viscosity and κ_i = Σ (axial spring stiffness) + k_glue at i (f already
//       holds −m̃·c·v, hence the (1 + dt·c)·v). Our reading of the seed's "semi FSAL formula for
//       mildly stiff problems" [Verlet 1967]: one force evaluation per step, at the state the
//       previous step ended in (first-same-as-last), an implicit velocity, and the position fed
//       by that new velocity. Since the Gershgorin bound gives λ_max(K) ≤ 2·max κ_i, the scheme is
//       stable at every dt for linear springs (docs/dynamics.md); the price is an artificial drag
//       of 1/(1 + dt²κ/m̃) per step on every motion, rigid translation included.
//
// Reads: springs, blocks, dynamics, glue, loads. Writes: particles (x, v of free particles in
// play), forces.
#include <vector>

#include "systems/deform/membrane.hpp"
#include "systems/deform/particle_set.hpp"

namespace phaco::deform {

Motion explicit_euler_step(Membrane& m, double dt_s);
Motion symplectic_euler_step(Membrane& m, double dt_s);

// `axial_stiffness` is scratch (one float per particle), reused between steps.
Motion semi_implicit_001_step(Membrane& m, double dt_s, std::vector<float>& axial_stiffness);

// κ_i of the particles in play (and of the sleeping ends of active springs): the diagonal the
// seed-001 step divides by, mN/mm. Deterministic for any thread count.
void sum_axial_stiffness(const Membrane& m, std::vector<float>& kappa);

}  // namespace phaco::deform
