#include "procedures/eye/eye_geometry.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <string>

#include "engine/core/error.hpp"

namespace phaco::eye {
namespace {

void require(bool ok, const std::string& message) {
  if (!ok) throw InputError("inconsistent eye parameters: " + message);
}

}  // namespace

double EyeGeometry::lens_volume() const {
  return 2.0 / 3.0 * std::numbers::pi * lens_a * lens_a * (lens_c_anterior + lens_c_posterior);
}

double EyeGeometry::lens_anterior_z(double r) const {
  const double q = r / lens_a;
  return lens_c_anterior * std::sqrt(std::max(0.0, 1.0 - q * q));
}

double EyeGeometry::lens_implicit(double x, double y, double z) const {
  const double c = z >= 0.0 ? lens_c_anterior : lens_c_posterior;
  return (x * x + y * y) / (lens_a * lens_a) + z * z / (c * c);
}

EyeGeometry eye_geometry(const EyeParams& p) {
  EyeGeometry g;
  g.lens_a = 0.5 * p.get("lens.equatorial_diameter_mm");
  g.lens_c_anterior = p.get("lens.anterior_half_thickness_mm");
  g.lens_c_posterior = p.get("lens.posterior_half_thickness_mm");
  g.nucleus_fraction = p.get("lens.nucleus_fraction");
  g.capsule_radius = p.get("capsule.radius_mm");
  require(g.nucleus_fraction < 1.0, "lens.nucleus_fraction must be below 1");
  require(g.capsule_radius < g.lens_a,
          "capsule.radius_mm must be below half of lens.equatorial_diameter_mm");

  g.cornea_posterior_apex_z = p.get("cornea.posterior_apex_z_mm");
  g.cornea_anterior_apex_z = g.cornea_posterior_apex_z + p.get("cornea.central_thickness_mm");
  g.cornea_anterior_radius = p.get("cornea.anterior_radius_mm");
  g.cornea_posterior_radius = p.get("cornea.posterior_radius_mm");
  g.cornea_anterior_centre_z = g.cornea_anterior_apex_z - g.cornea_anterior_radius;
  g.cornea_posterior_centre_z = g.cornea_posterior_apex_z - g.cornea_posterior_radius;
  g.limbus_radius = 0.5 * p.get("cornea.limbus_diameter_mm");
  require(g.limbus_radius < g.cornea_posterior_radius && g.limbus_radius < g.cornea_anterior_radius,
          "cornea.limbus_diameter_mm must be below twice each corneal radius");
  const double l2 = g.limbus_radius * g.limbus_radius;
  g.limbus_anterior_z = g.cornea_anterior_centre_z +
                        std::sqrt(g.cornea_anterior_radius * g.cornea_anterior_radius - l2);
  g.limbus_posterior_z = g.cornea_posterior_centre_z +
                         std::sqrt(g.cornea_posterior_radius * g.cornea_posterior_radius - l2);
  require(g.limbus_anterior_z > g.limbus_posterior_z,
          "the anterior corneal sphere (cornea.anterior_radius_mm) must stay in front of the "
          "posterior one (cornea.posterior_radius_mm) out to the limbus");
  require(
      g.cornea_posterior_apex_z > g.lens_c_anterior,
      "cornea.posterior_apex_z_mm must be in front of the lens (lens.anterior_half_thickness_mm)");

  g.iris_z = p.get("iris.z_mm");
  g.pupil_radius = 0.5 * p.get("iris.pupil_diameter_mm");
  const double dz = g.iris_z - g.cornea_posterior_centre_z;
  require(g.iris_z < g.cornea_posterior_apex_z && g.iris_z > g.limbus_posterior_z,
          "iris.z_mm must lie between the posterior cornea at the limbus and its apex");
  g.iris_outer_radius = std::sqrt(g.cornea_posterior_radius * g.cornea_posterior_radius - dz * dz);
  require(g.pupil_radius < g.iris_outer_radius,
          "iris.pupil_diameter_mm must be smaller than the iris (where the cornea meets z = "
          "iris.z_mm)");
  require(g.pupil_radius >= g.lens_a || g.lens_anterior_z(g.pupil_radius) < g.iris_z,
          "the lens must stay behind the iris at the pupil margin (iris.z_mm, lens thickness)");

  const double axial = p.get("globe.axial_length_mm");
  g.globe_radius = p.get("globe.radius_mm");
  g.globe_centre_z = g.cornea_anterior_apex_z - axial + g.globe_radius;
  const double eq_dz = g.globe_centre_z;  // lens equator is at z = 0
  require(std::hypot(g.lens_a, eq_dz) < g.globe_radius &&
              g.cornea_anterior_apex_z - axial < -g.lens_c_posterior,
          "the globe (globe.radius_mm, globe.axial_length_mm) must contain the lens");
  return g;
}

}  // namespace phaco::eye
