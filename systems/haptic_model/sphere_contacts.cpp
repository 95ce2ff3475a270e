// Lens material as contact spheres (issue 19 item 5): the sculpted nucleus, the fragment lens's
// cells, loose fragments under a chopper — any tool, one primitive. See proxy_planes.hpp.
//
// Why spheres: the tets lens is sculpted by removing tets whose centre the ultrasound sphere
// reaches (seed 000 §5.3's centre test) and the fragment lens is mass points (seed 002 §4), so a
// sphere per element at its centroid is the material exactly as the simulation removes and moves
// it; equal-volume spheres of neighbouring tets overlap (radius ≈ 0.30 of a regular tet's edge,
// centroids ≈ 0.41 apart), so their union has no holes the 0.45 mm tip could fall into.
#include <algorithm>
#include <cmath>

#include "systems/haptic_model/proxy_planes.hpp"

namespace phaco::haptic_model::detail {

uint32_t add_sphere_planes(const HapticTool& m, const Vec3& outside, const Vec3& device, double r,
                           double rigid_k, Planes& planes, uint32_t count, double& deepest) {
  const Vec3& proxy = outside;
  deepest = 0;
  struct Hit {
    uint32_t j;
    Vec3 n;
    double pen;
  };
  std::array<Hit, kMaxSphereContacts> hits;
  uint32_t nh = 0;
  const uint32_t ns = std::min(m.sphere_count, kHapticMaxSpheres);
  const double lead = (device - proxy).norm();
  for (uint32_t j = 0; j < ns; ++j) {
    const Vec3 c(m.sphere_x[j], m.sphere_y[j], m.sphere_z[j]);
    const double reach = r + double(m.sphere_r[j]);
    const Vec3 from_c = proxy - c;
    // n·(D − c) ≥ |P − c| − |D − P|: no penetration possible beyond this.
    if (from_c.squaredNorm() >= (reach + lead) * (reach + lead)) continue;
    const double len = from_c.norm();
    Vec3 n;
    if (len > 1e-9) {
      n = from_c / len;
    } else {  // the proxy at the centre (deep in a cut): out toward the device, else up
      const Vec3 d = device - c;
      n = d.norm() > 1e-9 ? Vec3(d / d.norm()) : Vec3::UnitZ();
    }
    const double pen = reach - n.dot(device - c);
    if (!(pen > 0)) continue;
    if (nh < kMaxSphereContacts) {
      hits[nh++] = {j, n, pen};
      continue;
    }
    uint32_t shallowest = 0;
    for (uint32_t k = 1; k < nh; ++k)
      if (hits[k].pen < hits[shallowest].pen) shallowest = k;
    if (pen > hits[shallowest].pen) hits[shallowest] = {j, n, pen};
  }
  if (nh == 0) return count;
  // A fixed order (by sphere index) so the solve does not depend on the replacement order above.
  std::sort(hits.begin(), hits.begin() + nh, [](const Hit& a, const Hit& b) { return a.j < b.j; });
  double total = 0;
  for (uint32_t k = 0; k < nh; ++k) total += hits[k].pen, deepest = std::max(deepest, hits[k].pen);
  const double cut = rigid_k > 0 ? 0.0 : std::max(0.0, double(m.cut_force_mn));
  for (uint32_t k = 0; k < nh && count < kMaxPlanes; ++k) {
    const Hit& h = hits[k];
    const double w = h.pen / total;
    const Vec3 c(m.sphere_x[h.j], m.sphere_y[h.j], m.sphere_z[h.j]);
    const double kj = rigid_k > 0 ? rigid_k : std::max(0.0, double(m.sphere_k[h.j]));
    planes[count++] = {h.n, c + double(m.sphere_r[h.j]) * h.n, kj * w, cut * w};
  }
  return count;
}

}  // namespace phaco::haptic_model::detail
