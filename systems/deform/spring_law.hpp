#pragma once
// One spring's force, energy and stiffness along its axis under the two laws (seed 000 §5.1
// quadratic, seeds 001/003 Hooke), shared by the deform passes so they agree to the bit with
// springs::add_spring_forces.
#include <cmath>

#include "components/springs.hpp"

namespace phaco::deform {

// Force magnitude, mN, positive when the spring pulls its ends together; ext = l − l0, mm.
inline float spring_magnitude(SpringLaw law, float k, float ext) {
  return law == SpringLaw::Linear ? k * ext : k * ext * std::fabs(ext);
}

// Elastic energy, mN·mm = µJ.
inline double spring_potential(SpringLaw law, double k, double ext) {
  return law == SpringLaw::Linear ? 0.5 * k * ext * ext : k * std::fabs(ext) * ext * ext / 3.0;
}

// dF/dl, mN/mm: the stiffness along the axis (the tangent of the quadratic law).
inline float spring_axial_stiffness(SpringLaw law, float k, float ext) {
  return law == SpringLaw::Linear ? k : 2.0f * k * std::fabs(ext);
}

}  // namespace phaco::deform
