#pragma once
// Derived eye geometry in the DESIGN.md §6 frame (origin at the lens equator centre, +z toward the
// surgeon), computed once from EyeParams and checked for consistency, so each mesh generator reads
// named lengths instead of re-deriving them.
#include "procedures/eye/eye_params.hpp"

namespace phaco::eye {

struct EyeGeometry {
  // Lens: two half-ellipsoids sharing the equator z = 0.
  double lens_a = 0;            // equatorial semi-axis, mm
  double lens_c_anterior = 0;   // anterior pole at z = +c, mm
  double lens_c_posterior = 0;  // posterior pole at z = -c, mm
  double nucleus_fraction = 0;  // nucleus = lens scaled by this about the origin
  double capsule_radius = 0;    // projected radius the anterior capsule mesh covers, mm

  double iris_z = 0;             // mm
  double pupil_radius = 0;       // mm
  double iris_outer_radius = 0;  // where the posterior corneal sphere crosses z = iris_z, mm

  double cornea_anterior_apex_z = 0;    // mm
  double cornea_posterior_apex_z = 0;   // mm
  double cornea_anterior_radius = 0;    // mm
  double cornea_posterior_radius = 0;   // mm
  double cornea_anterior_centre_z = 0;  // sphere centres on the axis, mm
  double cornea_posterior_centre_z = 0;
  double limbus_radius = 0;       // both corneal spheres are cut at this projected radius, mm
  double limbus_anterior_z = 0;   // z of the anterior sphere at the limbus, mm
  double limbus_posterior_z = 0;  // z of the posterior sphere at the limbus, mm

  double globe_radius = 0;    // mm
  double globe_centre_z = 0;  // posterior pole at cornea_anterior_apex_z - axial length, mm

  // (2/3)·π·a²·(c_anterior + c_posterior), mm³
  double lens_volume() const;
  // z of the anterior lens surface at projected radius r <= lens_a.
  double lens_anterior_z(double r) const;
  // (x²+y²)/a² + z²/c² with c the half-thickness of the side z is on; 1 on the lens surface.
  double lens_implicit(double x, double y, double z) const;
};

// Throws InputError with the offending parameter names when the numbers do not make an eye
// (e.g. capsule wider than the lens, iris outside the cornea, cornea thinner at the limbus than 0).
EyeGeometry eye_geometry(const EyeParams& params);

}  // namespace phaco::eye
