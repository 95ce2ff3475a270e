#pragma once
// Seed 001 §3.4's correction step: "at the end of each step a correction routine is applied to
// each particle in order to correct position and velocity according to the environment physical
// constraints". The environment is the lens below (two half-ellipsoids sharing the equator,
// semi-axes R, R, c with c the anterior or posterior half-thickness by the sign of z, centred at
// the origin) and the posterior cornea above (a sphere the membrane must stay inside).
//
// A free particle found inside the lens is moved to the lens surface. The nearest point on an
// ellipsoid has no closed form; we take up to three Newton steps on q(x) = 1 along the gradient
// of q (x ← x − (q − 1)·∇q/|∇q|², each a move along the local normal, exact for a sphere and
// within the square of the depth otherwise) and finish with a radial scaling that puts the point
// exactly on q = 1 (the last Newton step may overshoot by about the square of the depth). A
// particle deep inside (q < 1/4, never the case for a membrane lying on the lens) is scaled
// radially at once. A particle beyond the corneal sphere is put back on it radially (the exact
// nearest point). Either way the velocity's component into the obstacle is removed; the tangential
// and the outgoing components stay.
//
// Anchored and scripted particles are not corrected: a tool decides where they are.
//
// Reads: environment, particles (kind). Writes: particles (x, v of free particles in play).
#include <cstdint>

#include "systems/deform/membrane.hpp"

namespace phaco::deform {

// Returns how many particles were corrected. Deterministic for any thread count.
uint32_t apply_environment(Membrane& m);

// q(x) of the lens: < 1 inside, 1 on the surface.
double lens_level(const Environment& env, double x, double y, double z);

}  // namespace phaco::deform
