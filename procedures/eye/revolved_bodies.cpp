// Cornea, iris and globe: surfaces of revolution about the optical axis.
#include <cmath>
#include <numbers>

#include "procedures/eye/eye_geometry.hpp"
#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/revolve.hpp"

namespace phaco::eye {
namespace {

// Ring spacing giving about `vertices` vertices on a surface of the given area: triangles of
// area spacing²/√3, twice as many triangles as vertices.
double spacing_for(double area, double vertices) {
  return std::sqrt(std::sqrt(3.0) / 2.0 * area / vertices);
}

double total_area(const std::vector<MeridianCurve>& curves) {
  double a = 0.0;
  for (const auto& c : curves) a += c.swept_area();
  return a;
}

}  // namespace

SurfaceMesh make_cornea(const EyeParams& params, const Resolution& res) {
  const EyeGeometry g = eye_geometry(params);
  const double ra = g.cornea_anterior_radius, za = g.cornea_anterior_centre_z;
  const double rp = g.cornea_posterior_radius, zp = g.cornea_posterior_centre_z;
  const double theta_a = std::asin(g.limbus_radius / ra);
  const double theta_p = std::asin(g.limbus_radius / rp);
  // Apex -> limbus on the anterior sphere, down the rim band, limbus -> apex on the posterior one.
  std::vector<MeridianCurve> curves;
  curves.emplace_back(
      [=](double t) {
        return RZ{ra * std::sin(t), za + ra * std::cos(t)};
      },
      0.0, theta_a);
  curves.emplace_back(
      [=](double t) {
        return RZ{g.limbus_radius,
                  g.limbus_anterior_z + t * (g.limbus_posterior_z - g.limbus_anterior_z)};
      },
      0.0, 1.0);
  curves.emplace_back(
      [=](double t) {
        return RZ{rp * std::sin(theta_p - t), zp + rp * std::cos(theta_p - t)};
      },
      0.0, theta_p);
  const double spacing =
      spacing_for(total_area(curves), kCorneaVertexFraction * res.capsule_vertices);
  SurfaceMesh mesh = revolve(profile_rings(curves, spacing), spacing);
  orient_outward(mesh);
  return mesh;
}

SurfaceMesh make_iris(const EyeParams& params, const Resolution& res) {
  const EyeGeometry g = eye_geometry(params);
  std::vector<MeridianCurve> curves;
  curves.emplace_back(
      [=](double t) {
        return RZ{t, g.iris_z};
      },
      g.pupil_radius, g.iris_outer_radius);
  const double spacing =
      spacing_for(total_area(curves), kIrisVertexFraction * res.capsule_vertices);
  SurfaceMesh mesh = revolve(profile_rings(curves, spacing), spacing);
  orient_toward_plus_z(mesh);
  return mesh;
}

SurfaceMesh make_globe(const EyeParams& params, const Resolution& res) {
  const EyeGeometry g = eye_geometry(params);
  const double r = g.globe_radius, zc = g.globe_centre_z;
  std::vector<MeridianCurve> curves;
  curves.emplace_back(
      [=](double t) {
        return RZ{r * std::sin(t), zc + r * std::cos(t)};
      },
      0.0, std::numbers::pi);
  const double spacing =
      spacing_for(total_area(curves), kGlobeVertexFraction * res.capsule_vertices);
  SurfaceMesh mesh = revolve(profile_rings(curves, spacing), spacing);
  orient_outward(mesh);
  return mesh;
}

}  // namespace phaco::eye
