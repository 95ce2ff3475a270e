// The corneal port in the local model (issue 20 item 2: "the haptic device feels the port"). See
// proxy_planes.hpp for the planes and docs/haptic_model.md for why the port is a proxy constraint.
//
// Why planes of the proxy rather than a force added to the output: the device is held by the
// coupling k_c as the scene's hand spring holds the tool (tool_eye.hand_stiffness_mn_mm, both
// 1000 mN/mm by default), so the proxy solved against the tunnel gives the series k_c·k_t/(k_c +
// k_t) the scene's equilibrium has; the port then shares the proxy with the capsule patch and the
// lens (a tip pressed on the capsule while levering feels both), and its force is bounded and
// continuous as the other planes' are.
#include <algorithm>
#include <cmath>

#include "systems/haptic_model/proxy_planes.hpp"

namespace phaco::haptic_model::detail {

uint32_t add_port_planes(const HapticTool& m, const Vec3& device, const Vec3& shaft,
                         const Vec3& axis_offset, double r, Planes& planes, uint32_t count) {
  const double k = m.port_stiffness_mn_per_mm, len = shaft.norm();
  if (!m.port_present || !(k > 0) || !(len > 1e-9) || !std::isfinite(len)) return count;
  const Vec3 d = shaft / len;
  const Vec3 c(m.port_centre_mm[0], m.port_centre_mm[1], m.port_centre_mm[2]);
  const Vec3 a = Vec3(m.port_axis[0], m.port_axis[1], m.port_axis[2]).normalized();
  const Vec3 ew = Vec3(m.port_width_dir[0], m.port_width_dir[1], m.port_width_dir[2]).normalized();
  const Vec3 eh = a.cross(ew);
  // The tunnel holds the shaft's axis, through P + axis_offset (a bent point): the planes on P are
  // those of a centre moved back by the offset.
  const Vec3 ca = c - axis_offset;
  // In the port while the tip is past the outer opening and the centre is behind it along the
  // shaft (systems/tool_eye engaged_port's rule); the springs fade in from the tip at the centre
  // to the tip half a tunnel past it, so neither entering nor leaving is a step.
  const double half_length = std::max(1e-3, 0.5 * double(m.port_tunnel_length_mm));
  const double behind = (ca - device).dot(d), depth = (device - c).dot(a);
  const double weight = std::clamp(behind / half_length, 0.0, 1.0) *
                        std::clamp((depth + half_length) / half_length, 0.0, 1.0);
  if (!(weight > 0)) return count;
  for (int axis = 0; axis < 2; ++axis) {
    const Vec3& e = axis == 0 ? ew : eh;
    const double free = axis == 0 ? std::max(0.0, double(m.port_half_width_mm)) : 0.0;
    const Vec3 g = e - d.dot(e) * d;
    const double gn = g.norm();
    if (!(gn > 1e-6)) continue;  // the shaft along the slit's direction: no offset across it
    const Vec3 n = g / gn;
    for (const double side : {1.0, -1.0}) {
      if (count >= kMaxPlanes) return count;
      // pen = r − side·n·(P − point) = side·n·(c − P) − free/|g|: the offset past the free band.
      planes[count++] = {side * n, ca - side * (free / gn + r) * n, weight * k * gn * gn};
    }
  }
  return count;
}

}  // namespace phaco::haptic_model::detail
