#pragma once
// The default eye's corneal spheres and keratome, and the analytic line–sphere crossing the
// incision tests measure against.
#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>
#include <string>

#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_params.hpp"
#include "systems/incision/keratome.hpp"
#include "systems/incision/wound.hpp"
#include "tests/support/expect_invalid.hpp"

namespace phaco::incision::test {

inline CorneaSpheres default_spheres() {
  const eye::EyeGeometry g = eye::eye_geometry(eye::default_eye_params());
  return {g.cornea_anterior_centre_z, g.cornea_anterior_radius, g.cornea_posterior_centre_z,
          g.cornea_posterior_radius, g.limbus_radius};
}

inline KeratomeShape default_shape() {
  KeratomeShape s;
  s.width_mm = eye::default_eye_params().get("tools.keratome_width_mm");
  return s;
}

inline KeratomeBlade start_blade(const CorneaSpheres& s, double hour, double limbus_distance_mm,
                                 double angle_deg) {
  return incision_start_blade(s.anterior_centre_z, s.anterior_radius_mm, s.limbus_radius_mm,
                              {hour, limbus_distance_mm, angle_deg}, default_shape());
}

// Smallest t > 0 with |p + t·d − (0, 0, cz)| = R (d unit), solved here from the quadratic
// t² + 2(w·d)t + |w|² − R² = 0, w = p − C; throws when the line misses.
inline double line_sphere_far_root(const Vec3& p, const Vec3& d, double cz, double r) {
  const Vec3 w = p - Vec3(0, 0, cz);
  const double b = w.dot(d), c = w.squaredNorm() - r * r;
  const double disc = b * b - c;
  if (disc < 0) throw std::logic_error("line misses the sphere");
  const double t1 = -b - std::sqrt(disc), t2 = -b + std::sqrt(disc);
  return t1 > 0 ? t1 : t2;
}

using phaco::test::expect_invalid;

}  // namespace phaco::incision::test
