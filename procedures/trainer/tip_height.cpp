#include "procedures/trainer/tip_height.hpp"

#include <cmath>
#include <limits>

namespace phaco {

namespace {

// z of a sphere (centre on the axis at centre_z) on its upper side at radial distance rho.
double cap_z(double radius, double centre_z, double rho) {
  return centre_z + std::sqrt(std::max(0.0, radius * radius - rho * rho));
}

}  // namespace

TipHeight tip_height(const eye::EyeGeometry& g, bool capsule, const Vec3& p) {
  TipHeight out{std::numeric_limits<double>::quiet_NaN(), render::Tissue::None};
  if (!p.allFinite()) return out;
  const double rho = std::hypot(p.x(), p.y());
  struct Layer {
    double bottom, top;
    render::Tissue tissue;
  };
  Layer layers[2];
  int n = 0;
  if (rho < g.limbus_radius) {
    layers[n++] = {cap_z(g.cornea_posterior_radius, g.cornea_posterior_centre_z, rho),
                   cap_z(g.cornea_anterior_radius, g.cornea_anterior_centre_z, rho),
                   render::Tissue::Cornea};
  }
  if (rho < g.lens_a) {
    const double s = std::sqrt(std::max(0.0, 1.0 - (rho / g.lens_a) * (rho / g.lens_a)));
    const bool covered = capsule && rho < g.capsule_radius;
    layers[n++] = {-g.lens_c_posterior * s, g.lens_anterior_z(rho),
                   covered ? render::Tissue::Capsule : render::Tissue::Lens};
  }
  for (int i = 0; i < n; ++i) {
    const Layer& l = layers[i];
    if (p.z() >= l.bottom && p.z() <= l.top) return {p.z() - l.top, l.tissue};  // in it
    // The nearest top below the tip.
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
