#include "systems/incision/wound.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <stdexcept>
#include <string>

#include "systems/incision/port_arc.hpp"

namespace phaco::incision {
namespace {

void require_positive_radius(double v, const char* field) {
  if (!std::isfinite(v) || v <= 0.0)
    throw std::invalid_argument(std::string("cornea spheres: ") + field +
                                " must be a finite positive number (mm)");
}

WoundSection to_wound_section(const BladeSection& s) {
  return {s.touches, s.left, s.right, s.middle};
}

// A section is kept when it is strictly wider than the one held (the first of equals stays, so a
// blade resting fully in does not move the recorded wound by rounding).
void keep_widest(BladeSection& held, const BladeSection& now) {
  if (now.touches && (!held.touches || now.width_mm > held.width_mm)) held = now;
}

bool off_axis(const Vec3& p) {
  return p.x() != 0.0 || p.y() != 0.0;
}

}  // namespace

void check_spheres(const CorneaSpheres& s) {
  if (!std::isfinite(s.anterior_centre_z))
    throw std::invalid_argument("cornea spheres: anterior_centre_z is not finite");
  if (!std::isfinite(s.posterior_centre_z))
    throw std::invalid_argument("cornea spheres: posterior_centre_z is not finite");
  require_positive_radius(s.anterior_radius_mm, "anterior_radius_mm");
  require_positive_radius(s.posterior_radius_mm, "posterior_radius_mm");
  require_positive_radius(s.limbus_radius_mm, "limbus_radius_mm");
}

CornealWound measure_wound(const BladeSection& outer, const BladeSection& inner,
                           const Vec3& entry_axis, double penetration_depth_mm,
                           const CorneaSpheres& spheres) {
  CornealWound w;
  w.outer = to_wound_section(outer);
  w.inner = to_wound_section(inner);
  w.incised = outer.touches;
  w.penetrated = outer.touches && inner.touches;
  const double na = entry_axis.norm();
  if (na > 0.0 && std::isfinite(na)) {
    const double s = std::clamp(-entry_axis.z() / na, -1.0, 1.0);
    w.entry_angle_deg = std::asin(s) * 180.0 / std::numbers::pi;
  }
  if (w.incised) {
    w.width_mm = outer.width_mm;
    w.clock_hour = clock_hour_of(outer.middle);
    w.limbus_distance_mm =
        spheres.limbus_radius_mm - std::hypot(outer.middle.x(), outer.middle.y());
  }
  if (w.penetrated) {
    w.inner_width_mm = inner.width_mm;
    w.tunnel_length_mm = (inner.middle - outer.middle).norm();
    w.penetration_depth_mm = penetration_depth_mm;
  }
  return w;
}

WoundFrame update_wound(WoundTracker& t, const KeratomeBlade& blade, const CorneaSpheres& spheres) {
  check_spheres(spheres);
  const BladeFrame f = blade_frame(blade);
  WoundFrame now;
  now.outer = blade_section(blade, spheres.anterior_centre_z, spheres.anterior_radius_mm);
  now.inner = blade_section(blade, spheres.posterior_centre_z, spheres.posterior_radius_mm);

  ++t.frames;
  if (now.outer.touches) ++t.cutting_frames;
  if (!t.punctured && now.outer.touches && now.outer.has_puncture) {
    t.punctured = true;
    t.entry_axis = f.d;
    t.outer_puncture = now.outer.puncture;
  }
  keep_widest(t.outer, now.outer);
  if (t.punctured) {
    keep_widest(t.inner, now.inner);
    if (now.inner.has_puncture && now.inner.touches) {
      const double depth = (f.tip - now.inner.puncture).dot(f.d);
      t.penetration_depth_mm = std::max(t.penetration_depth_mm, depth);
    }
  }
  t.wound = measure_wound(t.outer, t.inner, t.entry_axis, t.penetration_depth_mm, spheres);

  // The port's span follows the outer cut ends of this frame (enlargement, reorientation); its
  // radius and height are those of the widest outer section's ends, so a withdrawing blade's
  // shrinking section does not pull the port toward the puncture.
  if (now.outer.touches && !now.outer.closed && off_axis(now.outer.left) &&
      off_axis(now.outer.right)) {
    widen_port(t.port, now.outer.left, now.outer.right);
    const BladeSection& o = t.outer;
    t.port.radius_mm =
        0.5 * (std::hypot(o.left.x(), o.left.y()) + std::hypot(o.right.x(), o.right.y()));
    t.port.z_mm = 0.5 * (o.left.z() + o.right.z());
  }
  return now;
}

}  // namespace phaco::incision
