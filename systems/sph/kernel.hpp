#pragma once
// The SPH smoothing kernel of fragment contact: poly6 with support h (seed 002 §6.1 "a 6th order
// smoothing kernel in a support h, as described in [MCG03]"; Müller, Charypar, Gross 2003, eq. 20):
//
//   W(r, h) = 315 / (64 π h⁹) · (h² − r²)³   for 0 ≤ r ≤ h, 0 beyond;   ∫ W dV = 1,
//   ∇W(r, h) = −945 / (32 π h⁹) · (h² − r²)² · r      (r the vector from the neighbour to the
//   particle).
//
// Both depend on r only through r², so no square root is needed to evaluate them. The gradient's
// magnitude 945/(32πh⁹)·|r|·(h² − r²)² peaks at |r| = h/√5 and vanishes at r = 0 (MCG03 §3.5: the
// reason they use the spiky kernel for pressure); the contact force (contact.hpp) therefore holds
// the gradient at its peak inside h/√5.
//
// Reads and writes nothing: pure functions.
#include <numbers>

namespace phaco::sph {

// 315 / (64 π h⁹).
inline double poly6_normalisation(double h) {
  const double h3 = h * h * h;
  return 315.0 / (64.0 * std::numbers::pi * h3 * h3 * h3);
}

// W from r² (mm⁻³); 0 at and beyond the support.
inline double poly6(double r2, double h) {
  const double d = h * h - r2;
  return d > 0.0 ? poly6_normalisation(h) * d * d * d : 0.0;
}

// ∇W = grad_scale · r (mm⁻⁴ per mm of r): the factor multiplying the vector r = x_i − x_j.
inline double poly6_gradient_scale(double r2, double h) {
  const double d = h * h - r2;
  return d > 0.0 ? -6.0 * poly6_normalisation(h) * d * d : 0.0;
}

// Where |∇W| peaks: r = h/√5.
inline double poly6_gradient_peak_radius(double h) {
  return h / 2.23606797749978969641;  // √5
}

// |∇W| at its peak: 945/(32πh⁹) · (h/√5) · (4h²/5)².
inline double poly6_gradient_peak(double h) {
  const double r = poly6_gradient_peak_radius(h);
  return -poly6_gradient_scale(r * r, h) * r;
}

}  // namespace phaco::sph
