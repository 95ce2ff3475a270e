#include "procedures/lens/nucleus_groove.hpp"

#include <cmath>

namespace phaco::lens {

std::vector<uint32_t> groove_cells(const SimplexCells& cells, const CrossGroove& g) {
  std::vector<uint32_t> out;
  const double a = g.first_angle_deg * M_PI / 180.0;
  const Vec3 d0(std::cos(a), std::sin(a), 0), d1(-std::sin(a), std::cos(a), 0);
  const double half = 0.5 * g.width_mm, r2n = g.nucleus_radius_mm * g.nucleus_radius_mm;
  for (uint32_t c = 0; c < cells.size(); ++c) {
    if (!cells.alive[c]) continue;
    const Vec3 p(cells.rest_x[c], cells.rest_y[c], cells.rest_z[c]);
    const Vec3 q(p.x() - g.centre_mm.x(), p.y() - g.centre_mm.y(), 0);
    bool in_arm = false;
    for (const Vec3& d : {d0, d1}) {
      const double along = q.dot(d), across = std::abs(q.x() * d.y() - q.y() * d.x());
      in_arm |= std::abs(along) <= g.arm_length_mm && across <= half;
    }
    if (!in_arm) continue;
    const double rr = (p.x() * p.x() + p.y() * p.y()) / r2n;
    if (rr >= 1) continue;  // beyond the nucleus: the trench ends in it
    const double s = std::sqrt(1 - rr);
    const double top = g.nucleus_anterior_mm * s, bottom = -g.nucleus_posterior_mm * s;
    if (p.z() > top - g.depth_fraction * (top - bottom)) out.push_back(c);
  }
  return out;
}

}  // namespace phaco::lens
