#include "procedures/trainer/tip_height.hpp"

#include <cmath>
#include <limits>

#include "procedures/eye/eye_params.hpp"

namespace phaco {

TipHeightGeometry tip_height_geometry(const eye::EyeParams& p, bool has_capsule) {
  TipHeightGeometry g;
  g.cornea_posterior_radius_mm = p.get("cornea.posterior_radius_mm");
  g.cornea_posterior_apex_z_mm = p.get("cornea.posterior_apex_z_mm");
  g.cornea_anterior_radius_mm = p.get("cornea.anterior_radius_mm");
  g.cornea_anterior_apex_z_mm = g.cornea_posterior_apex_z_mm + p.get("cornea.central_thickness_mm");
  g.limbus_radius_mm = 0.5 * p.get("cornea.limbus_diameter_mm");
  g.lens_equator_radius_mm = 0.5 * p.get("lens.equatorial_diameter_mm");
  g.lens_anterior_mm = p.get("lens.anterior_half_thickness_mm");
  g.lens_posterior_mm = p.get("lens.posterior_half_thickness_mm");
  g.capsule = has_capsule;
  return g;
}

namespace {

// z of a sphere's upper cap (apex at apex_z) at radial distance rho; NaN beyond the sphere.
double cap_z(double radius, double apex_z, double rho) {
  const double s = radius * radius - rho * rho;
  return s < 0 ? std::numeric_limits<double>::quiet_NaN() : apex_z - radius + std::sqrt(s);
}

}  // namespace

TipHeight tip_height(const TipHeightGeometry& g, const Vec3& p) {
  TipHeight out{std::numeric_limits<double>::quiet_NaN(), render::Tissue::None};
  if (!p.allFinite()) return out;
  const double rho = std::hypot(p.x(), p.y());
  struct Layer {
    double bottom, top;
    render::Tissue tissue;
  };
  Layer layers[2];
  int n = 0;
  if (rho < g.limbus_radius_mm) {
    const double top = cap_z(g.cornea_anterior_radius_mm, g.cornea_anterior_apex_z_mm, rho);
    const double bottom = cap_z(g.cornea_posterior_radius_mm, g.cornea_posterior_apex_z_mm, rho);
    if (std::isfinite(top) && std::isfinite(bottom))
      layers[n++] = {bottom, top, render::Tissue::Cornea};
  }
  if (rho < g.lens_equator_radius_mm) {
    const double s =
        std::sqrt(1.0 - (rho / g.lens_equator_radius_mm) * (rho / g.lens_equator_radius_mm));
    layers[n++] = {-g.lens_posterior_mm * s, g.lens_anterior_mm * s,
                   g.capsule ? render::Tissue::Capsule : render::Tissue::Lens};
  }
  for (int i = 0; i < n; ++i) {
    const Layer& l = layers[i];
    if (p.z() >= l.bottom && p.z() <= l.top) return {p.z() - l.top, l.tissue};  // in it
    // The highest top below the tip (the cornea lies above the lens: checked first).
    if (p.z() > l.top && !(out.height_mm <= p.z() - l.top)) out = {p.z() - l.top, l.tissue};
  }
  return out;
}

HeightBand height_band(double h) {
  if (!std::isfinite(h)) return HeightBand::None;
  if (h < 0) return HeightBand::In;
  return h <= kTouchingMm ? HeightBand::Touching : HeightBand::Above;
}

}  // namespace phaco
