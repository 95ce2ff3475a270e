// The tip sphere against the published patch; see patch_contacts.hpp.
#include "systems/haptic_model/patch_contacts.hpp"

#include <algorithm>
#include <cmath>

#include "systems/haptic_model/local_nodes.hpp"

namespace phaco::haptic_model::detail {
namespace {

// Keeps the kHapticMaxContacts deepest (a tip sphere smaller than the cells never presses more).
void insert_contact(const HapticContact& c, std::array<HapticContact, kHapticMaxContacts>& list,
                    uint32_t& count) {
  if (count < kHapticMaxContacts) {
    list[count++] = c;
    return;
  }
  uint32_t shallowest = 0;
  for (uint32_t k = 1; k < count; ++k) {
    if (list[k].penetration_mm < list[shallowest].penetration_mm) shallowest = k;
  }
  if (c.penetration_mm > list[shallowest].penetration_mm) list[shallowest] = c;
}

// The proxy's energy at p (solve_proxy's objective).
double proxy_energy(const Vec3& p, const Vec3& d, double kc, double r, const Planes& planes,
                    uint32_t count) {
  double e = 0.5 * kc * (p - d).squaredNorm();
  for (uint32_t j = 0; j < count; ++j) {
    const Plane& pl = planes[j];
    const double pen = r - pl.normal.dot(p - pl.point);
    if (!(pen > 0)) continue;
    if (pl.cap > 0 && pl.k * pen > pl.cap) {
      e += pl.cap * pen - 0.5 * pl.cap * pl.cap / pl.k;
    } else {
      e += 0.5 * pl.k * pen * pen;
    }
  }
  return e;
}

}  // namespace

void closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c,
                         std::array<double, 3>& w, bool& inside) {
  inside = false;
  const Vec3 ab = b - a, ac = c - a, ap = p - a;
  const double d1 = ab.dot(ap), d2 = ac.dot(ap);
  if (d1 <= 0 && d2 <= 0) return void(w = {1, 0, 0});
  const Vec3 bp = p - b;
  const double d3 = ab.dot(bp), d4 = ac.dot(bp);
  if (d3 >= 0 && d4 <= d3) return void(w = {0, 1, 0});
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) {
    const double v = d1 / (d1 - d3);
    return void(w = {1 - v, v, 0});
  }
  const Vec3 cp = p - c;
  const double d5 = ab.dot(cp), d6 = ac.dot(cp);
  if (d6 >= 0 && d5 <= d6) return void(w = {0, 0, 1});
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) {
    const double v = d2 / (d2 - d6);
    return void(w = {1 - v, 0, v});
  }
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
    const double v = (d4 - d3) / ((d4 - d3) + (d5 - d6));
    return void(w = {0, 1 - v, v});
  }
  const double denom = 1.0 / (va + vb + vc);
  const double v = vb * denom, u = vc * denom;
  w = {1 - v - u, v, u};
  inside = true;
}

void compute_normals(const HapticSlot& s, HapticScratch& sc) {
  const HapticTool& m = s.model;
  const uint32_t nt = std::min(m.triangle_count, kHapticMaxTriangles);
  for (uint32_t t = 0; t < nt; ++t) {
    const auto& tri = m.triangles[t];
    sc.tvalid[t] = 0;
    if (tri[0] >= m.node_count || tri[1] >= m.node_count || tri[2] >= m.node_count) continue;
    const Vec3 a = node(s, tri[0]);
    Vec3 n = (node(s, tri[1]) - a).cross(node(s, tri[2]) - a);
    const double len = n.norm();
    if (!(len > 1e-12)) continue;
    n /= len;
    sc.tnx[t] = n.x(), sc.tny[t] = n.y(), sc.tnz[t] = n.z(), sc.td[t] = n.dot(a);
    const Vec3 b = node(s, tri[1]), c = node(s, tri[2]), centre = (a + b + c) / 3.0;
    sc.tcx[t] = centre.x(), sc.tcy[t] = centre.y(), sc.tcz[t] = centre.z();
    sc.trad[t] = std::sqrt(std::max(
        {(a - centre).squaredNorm(), (b - centre).squaredNorm(), (c - centre).squaredNorm()}));
    sc.tvalid[t] = 1;
  }
}

void gather_contacts(const HapticSlot& s, const HapticScratch& sc, const Vec3& q, double r,
                     const HapticSettings& st, std::array<HapticContact, kHapticMaxContacts>& list,
                     uint32_t& count) {
  const HapticTool& m = s.model;
  const uint32_t nt = std::min(m.triangle_count, kHapticMaxTriangles);
  const uint16_t g = m.grasped_node;
  for (uint32_t t = 0; t < nt; ++t) {
    if (!sc.tvalid[t]) continue;
    const auto& tri = m.triangles[t];
    if (tri[0] == g || tri[1] == g || tri[2] == g) continue;  // the forceps hold this part
    const Vec3 n = Vec3(sc.tnx[t], sc.tny[t], sc.tnz[t]) * double(s.side[t]);
    const double sd = n.dot(q) - double(s.side[t]) * sc.td[t];  // signed, tool side positive
    if (sd > r || sd < -st.contact_max_depth_mm) continue;
    const double reach = sc.trad[t] + std::max(r, -sd);  // the sphere cannot touch it from further
    const double ex = q.x() - sc.tcx[t], ey = q.y() - sc.tcy[t], ez = q.z() - sc.tcz[t];
    if (ex * ex + ey * ey + ez * ez > reach * reach) continue;
    const Vec3 a = node(s, tri[0]), b = node(s, tri[1]), c = node(s, tri[2]);
    HapticContact hc;
    bool inside = false;
    closest_on_triangle(q, a, b, c, hc.w, inside);
    hc.point = hc.w[0] * a + hc.w[1] * b + hc.w[2] * c;
    hc.triangle = t;
    if (inside) {
      hc.normal = n;
      hc.penetration_mm = r - sd;
      hc.weight = 1;
    } else {
      const Vec3 d = q - hc.point;
      const double dist = d.norm();
      const double along = n.dot(d);
      if ((d - along * n).norm() <= 1e-9 * (1 + dist)) {  // projects onto the rim: the face's own
        hc.normal = n;
        hc.penetration_mm = r - sd;
        hc.weight = 1;
        if (hc.penetration_mm > 0) insert_contact(hc, list, count);
        continue;
      }
      // Beside the face: the sphere against its nearest edge or corner, from the tool's side only
      // (from behind, the neighbouring face holds it). Its share fades with the angle between
      // its direction and the face's normal, so a tip sliding round the edge loses it smoothly.
      if (along <= 0 || !(dist > 1e-12)) continue;
      hc.normal = d / dist;
      hc.penetration_mm = r - dist;
      hc.weight = along / dist;
    }
    if (hc.penetration_mm > 0) insert_contact(hc, list, count);
  }
  // Shares ω_j = φ_j·pen_j / max(Σ φ·pen, max pen), φ the edge fade (1 on a face): a facet
  // entering or leaving the contact does so with zero weight (continuous force), coplanar facets
  // (a vertex shared by six) act as one plane, and a lone fading edge fades out.
  double total = 0, deepest = 0;
  for (uint32_t k = 0; k < count; ++k) {
    total += list[k].weight * list[k].penetration_mm;
    deepest = std::max(deepest, list[k].penetration_mm);
  }
  const double denom = std::max(total, deepest);
  for (uint32_t k = 0; k < count; ++k)
    list[k].weight = list[k].weight * list[k].penetration_mm / denom;
}

Vec3 solve_proxy(const Vec3& d, const Vec3& start, double kc, double r, const Planes& planes,
                 uint32_t count) {
  Vec3 p = finite(start) ? start : d;
  if (proxy_energy(d, d, kc, r, planes, count) < proxy_energy(p, d, kc, r, planes, count)) p = d;
  double e = proxy_energy(p, d, kc, r, planes, count);
  for (int iter = 0; iter < 12; ++iter) {
    Eigen::Matrix3d a = kc * Eigen::Matrix3d::Identity();
    Vec3 b = kc * d;
    for (uint32_t j = 0; j < count; ++j) {
      const Plane& pl = planes[j];
      const double pen = r - pl.normal.dot(p - pl.point);
      if (!(pen > 0)) continue;
      if (pl.cap > 0 && pl.k * pen > pl.cap) {  // yielding: a constant push, no stiffness
        b += pl.cap * pl.normal;
        continue;
      }
      a += pl.k * pl.normal * pl.normal.transpose();
      b += pl.k * pl.normal * (pl.normal.dot(pl.point) + r);
    }
    const Vec3 step = a.ldlt().solve(b) - p;
    double alpha = 1.0, e1 = proxy_energy(p + step, d, kc, r, planes, count);
    while (e1 > e && alpha > 1e-6) {
      alpha *= 0.5;
      e1 = proxy_energy(p + alpha * step, d, kc, r, planes, count);
    }
    if (e1 > e) break;
    p += alpha * step;
    const bool done = alpha == 1.0 && e - e1 <= 1e-15 * (1 + e);
    e = e1;
    if (done || step.norm() * alpha < 1e-12) break;
  }
  return p;
}

}  // namespace phaco::haptic_model::detail
