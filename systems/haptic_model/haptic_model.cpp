// The haptic thread's local force model: see haptic_model.hpp and docs/haptic_model.md.
// Everything here works on the fixed arrays of HapticToolState: no allocation, no lock, no throw.
// One file because every part (proxy, implicit local nodes, grasp, lens, coupling, crossfade) is
// one tick's pipeline over the same state; splitting it by job is left to issue 22.
#include "systems/haptic_model/haptic_model.hpp"

#include <algorithm>
#include <cmath>

#include "systems/haptic_model/proxy_planes.hpp"

namespace phaco::haptic_model {
namespace {

using detail::Plane;
using detail::Planes;

constexpr double kHalfPi = 1.57079632679489661923;
constexpr int kArcSamples = 33;  // 32 intervals per quarter meridian

struct ArcTable {
  std::array<double, kArcSamples> c{}, s{};
};

// cos/sin of the scan angles, built once (a function-local static: after the first call, reading
// it is a plain load).
const ArcTable& arc_table() {
  static const ArcTable table = [] {
    ArcTable t;
    for (int k = 0; k < kArcSamples; ++k) {
      const double th = kHalfPi * k / (kArcSamples - 1);
      t.c[k] = std::cos(th), t.s[k] = std::sin(th);
    }
    return t;
  }();
  return table;
}

bool finite(const Vec3& v) {
  return std::isfinite(v.x()) && std::isfinite(v.y()) && std::isfinite(v.z());
}

Vec3 node(const HapticSlot& s, uint32_t i) {
  return {s.x[i], s.y[i], s.z[i]};
}

// Closest point on triangle abc to p (Ericson, Real-Time Collision Detection §5.1.5), as
// barycentric weights; `inside` when it lies in the face's interior (not on an edge or corner).
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

// Contacts of the tip sphere at q with the patch, on each triangle's remembered side.
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

// argmin ½k_c|P − D|² + Σ E_j(max(0, r − n_j·(P − p_j))), E_j the plane's energy (½k·pen², linear
// past its cap: proxy_planes.hpp): a strongly convex, piecewise quadratic energy. Newton on the
// piece the current P lies in (its 3×3 system solved exactly), with backtracking on the energy:
// plain piece-hopping can cycle between the pieces of a stiff valley (the proxy jumped tangentially
// there), the line search cannot. Warm-started from the last proxy; ≤ 12 rounds (2–3 typical).
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

// y = K·x over the stored spring blocks plus the grasp and contact springs (all nodes; the caller
// masks). K is the stiffness (−∂f/∂x), positive semidefinite.
void apply_stiffness(const HapticSlot& s, const HapticScratch& sc, uint32_t grasped, double kc,
                     const std::array<HapticContact, kHapticMaxContacts>& contacts,
                     uint32_t ncontacts, double ks, const double* x, double* y) {
  const HapticTool& m = s.model;
  const uint32_t n = m.node_count;
  std::fill(y, y + 3 * n, 0.0);
  const uint32_t ns = std::min(m.spring_count, kHapticMaxSprings);
  for (uint32_t k = 0; k < ns; ++k) {
    const uint32_t i = m.spring_i[k], j = m.spring_j[k];
    if (i >= n || j >= n) continue;
    const double ex = x[3 * i] - x[3 * j], ey = x[3 * i + 1] - x[3 * j + 1],
                 ez = x[3 * i + 2] - x[3 * j + 2];
    const double proj = sc.sa[k] * (sc.sdx[k] * ex + sc.sdy[k] * ey + sc.sdz[k] * ez);
    const double tx = proj * sc.sdx[k] + sc.sb[k] * ex, ty = proj * sc.sdy[k] + sc.sb[k] * ey,
                 tz = proj * sc.sdz[k] + sc.sb[k] * ez;
    y[3 * i] += tx, y[3 * i + 1] += ty, y[3 * i + 2] += tz;
    y[3 * j] -= tx, y[3 * j + 1] -= ty, y[3 * j + 2] -= tz;
  }
  if (grasped < n) {
    for (int c = 0; c < 3; ++c) y[3 * grasped + c] += kc * x[3 * grasped + c];
  }
  for (uint32_t c = 0; c < ncontacts; ++c) {
    const HapticContact& hc = contacts[c];
    const auto& tri = m.triangles[hc.triangle];
    double sdot = 0;
    for (int v = 0; v < 3; ++v) {
      const uint32_t i = tri[v];
      sdot += hc.w[v] * (hc.normal.x() * x[3 * i] + hc.normal.y() * x[3 * i + 1] +
                         hc.normal.z() * x[3 * i + 2]);
    }
    for (int v = 0; v < 3; ++v) {
      const uint32_t i = tri[v];
      const double f = ks * hc.weight * hc.w[v] * sdot;
      y[3 * i] += f * hc.normal.x(), y[3 * i + 1] += f * hc.normal.y(),
          y[3 * i + 2] += f * hc.normal.z();
    }
  }
}

void reset_nodes(HapticSlot& s) {
  const HapticTool& m = s.model;
  for (uint32_t i = 0; i < m.node_count; ++i) {
    s.x[i] = m.x[i], s.y[i] = m.y[i], s.z[i] = m.z[i];
    s.vx[i] = m.vx[i], s.vy[i] = m.vy[i], s.vz[i] = m.vz[i];
  }
  std::fill(s.warm_dv.begin(), s.warm_dv.end(), 0.0);
}

// The forces on the nodes at the start of the step into sc.rhs (springs, seed 003 §E.1; damping,
// §E.2–3; the forceps' coupling; the patch reaction) and the diagonal of their stiffness into
// sc.diag, with each spring's block (sc.sa, sb, sdx..sdz) for the stiffness product.
void accumulate_forces(const HapticSlot& s, HapticScratch& sc, const Vec3& dev, double kc,
                       double ks, double r,
                       const std::array<HapticContact, kHapticMaxContacts>& contacts,
                       uint32_t ncontacts, uint32_t grasped, double damping) {
  const HapticTool& m = s.model;
  const uint32_t n = m.node_count;
  // Forces at the start of the step (into rhs for now) and the spring blocks.
  double* f = sc.rhs.data();
  std::fill(f, f + 3 * n, 0.0);
  std::fill(sc.diag.begin(), sc.diag.begin() + 3 * n, 0.0);
  const uint32_t ns = std::min(m.spring_count, kHapticMaxSprings);
  for (uint32_t k = 0; k < ns; ++k) {
    const uint32_t i = m.spring_i[k], j = m.spring_j[k];
    sc.sa[k] = sc.sb[k] = sc.sdx[k] = sc.sdy[k] = sc.sdz[k] = 0;
    if (i >= n || j >= n) continue;
    const double dx = s.x[j] - s.x[i], dy = s.y[j] - s.y[i], dz = s.z[j] - s.z[i];
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (!(l > 1e-12)) continue;
    const double kk = m.k_mn_per_mm[k], l0 = m.rest_mm[k];
    const double ux = dx / l, uy = dy / l, uz = dz / l;
    const double fs = kk * (l - l0);  // Hooke (seed 003 §E.1), pulls i toward j when stretched
    f[3 * i] += fs * ux, f[3 * i + 1] += fs * uy, f[3 * i + 2] += fs * uz;
    f[3 * j] -= fs * ux, f[3 * j + 1] -= fs * uy, f[3 * j + 2] -= fs * uz;
    // −∂f/∂x = k·[(l0/l)·d̂d̂ᵀ + (1 − l0/l)·I]; the transverse part clamped at ≥ 0 (compression
    // would make it negative: the block stays positive semidefinite, CG stays valid).
    const double beta = std::max(0.0, 1.0 - l0 / l);
    sc.sa[k] = kk * (1.0 - beta), sc.sb[k] = kk * beta;
    sc.sdx[k] = ux, sc.sdy[k] = uy, sc.sdz[k] = uz;
    const double dg[3] = {sc.sa[k] * ux * ux + sc.sb[k], sc.sa[k] * uy * uy + sc.sb[k],
                          sc.sa[k] * uz * uz + sc.sb[k]};
    for (int c = 0; c < 3; ++c) sc.diag[3 * i + c] += dg[c], sc.diag[3 * j + c] += dg[c];
  }
  // Seed 003 §E.2–3: damping and viscoelastic force −(k_d + k_v)·v.
  for (uint32_t i = 0; i < n; ++i) {
    f[3 * i] -= damping * s.vx[i], f[3 * i + 1] -= damping * s.vy[i],
        f[3 * i + 2] -= damping * s.vz[i];
  }
  if (grasped < n) {  // the forceps: the grasped node held to the device by the coupling
    const Vec3 e = node(s, grasped) - dev;
    for (int c = 0; c < 3; ++c) f[3 * grasped + c] -= kc * e[c], sc.diag[3 * grasped + c] += kc;
  }
  for (uint32_t c = 0; c < ncontacts; ++c) {  // the patch reaction, barycentric on the corners
    const HapticContact& hc = contacts[c];
    const auto& tri = m.triangles[hc.triangle];
    const Vec3 pt =
        hc.w[0] * node(s, tri[0]) + hc.w[1] * node(s, tri[1]) + hc.w[2] * node(s, tri[2]);
    const double pen = r - hc.normal.dot(dev - pt), kw = ks * hc.weight;
    for (int v = 0; v < 3; ++v) {
      const uint32_t i = tri[v];
      for (int a = 0; a < 3; ++a) {
        f[3 * i + a] -= kw * pen * hc.w[v] * hc.normal[a];
        sc.diag[3 * i + a] += kw * hc.w[v] * hc.w[v] * hc.normal[a] * hc.normal[a];
      }
    }
  }
}

// Backward Euler on the unknown nodes: (M + dt·c·I + dt²·K)·Δv = dt·(f − dt·K·v) by Jacobi-
// preconditioned CG from last step's Δv; the forces are in sc.rhs (accumulate_forces). Returns the
// CG iterations, or 0 when nothing holds or presses the nodes and they are at rest (they sleep).
int backward_euler_step(HapticSlot& s, HapticScratch& sc, double kc, double ks,
                        const std::array<HapticContact, kHapticMaxContacts>& contacts,
                        uint32_t ncontacts, uint32_t grasped, double damping,
                        const HapticSettings& st, bool& ok) {
  const HapticTool& m = s.model;
  const uint32_t n = m.node_count;
  const double dt = st.dt_s;
  const double* f = sc.rhs.data();
  if (ncontacts == 0 && grasped >= n) {  // nothing holds or presses the nodes: at rest, sleep
    double fmax = 0, vmax = 0;
    for (uint32_t i = 0; i < n; ++i) {
      if (!sc.unknown[i]) continue;
      fmax = std::max({fmax, std::abs(f[3 * i]), std::abs(f[3 * i + 1]), std::abs(f[3 * i + 2])});
      vmax = std::max({vmax, std::abs(s.vx[i]), std::abs(s.vy[i]), std::abs(s.vz[i])});
    }
    if (fmax < st.sleep_force_mn && vmax < 1e-6) return 0;
  }
  for (uint32_t i = 0; i < 3 * n; ++i) {
    sc.u3[i] = sc.unknown[i / 3];
    sc.m3[i] = sc.u3[i] * (m.mass[i / 3] + dt * damping);
  }
  // (M + dt·c·I + dt²·K)·Δv = dt·(f − dt·K·v), v over the unknowns only (fixed nodes do not
  // move).
  double* v = sc.p.data();
  for (uint32_t i = 0; i < n; ++i) {
    const double u = sc.unknown[i];
    v[3 * i] = u * s.vx[i], v[3 * i + 1] = u * s.vy[i], v[3 * i + 2] = u * s.vz[i];
  }
  apply_stiffness(s, sc, grasped, kc, contacts, ncontacts, ks, v, sc.q.data());
  double* b = sc.rhs.data();  // overwrites f in place
  double bnorm2 = 0;
  const double dt2 = dt * dt;
  for (uint32_t i = 0; i < 3 * n; ++i) {
    b[i] = sc.u3[i] * dt * (f[i] - dt * sc.q[i]);
    sc.diag[i] = std::max(sc.m3[i] + dt2 * sc.diag[i], 1e-300);
    bnorm2 += b[i] * b[i];
  }
  auto apply_a = [&](const double* x, double* y) {
    apply_stiffness(s, sc, grasped, kc, contacts, ncontacts, ks, x, y);
    for (uint32_t i = 0; i < 3 * n; ++i) y[i] = sc.m3[i] * x[i] + sc.u3[i] * dt2 * y[i];
  };
  double* x = sc.dv.data();
  for (uint32_t i = 0; i < 3 * n; ++i) x[i] = sc.u3[i] * s.warm_dv[i];
  apply_a(x, sc.q.data());
  double rz = 0, r2 = 0;
  for (uint32_t i = 0; i < 3 * n; ++i) {
    sc.r[i] = b[i] - sc.q[i];
    sc.zr[i] = sc.r[i] / sc.diag[i];
    sc.p[i] = sc.zr[i];
    rz += sc.r[i] * sc.zr[i], r2 += sc.r[i] * sc.r[i];
  }
  const double tol2 = st.solver_tolerance * st.solver_tolerance * bnorm2;
  int it = 0;
  while (it < st.solver_iterations && r2 > tol2 && rz > 0) {
    apply_a(sc.p.data(), sc.q.data());
    double pq = 0;
    for (uint32_t i = 0; i < 3 * n; ++i) pq += sc.p[i] * sc.q[i];
    if (!(pq > 0)) break;
    const double alpha = rz / pq;
    double rz1 = 0;
    r2 = 0;
    for (uint32_t i = 0; i < 3 * n; ++i) {
      x[i] += alpha * sc.p[i];
      sc.r[i] -= alpha * sc.q[i];
      sc.zr[i] = sc.r[i] / sc.diag[i];
      rz1 += sc.r[i] * sc.zr[i], r2 += sc.r[i] * sc.r[i];
    }
    const double beta = rz1 / rz;
    rz = rz1;
    for (uint32_t i = 0; i < 3 * n; ++i) sc.p[i] = sc.zr[i] + beta * sc.p[i];
    ++it;
  }
  for (uint32_t i = 0; i < n; ++i) {
    if (!sc.unknown[i]) continue;
    s.vx[i] += x[3 * i], s.vy[i] += x[3 * i + 1], s.vz[i] += x[3 * i + 2];
    s.x[i] += dt * s.vx[i], s.y[i] += dt * s.vy[i], s.z[i] += dt * s.vz[i];
  }
  std::copy(x, x + 3 * n, s.warm_dv.begin());
  for (uint32_t i = 0; i < n; ++i) {
    if (!(std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && std::isfinite(s.z[i]))) ok = false;
  }
  return it;
}

// One step of the local nodes (backward Euler, or symplectic Euler for comparison). Returns the CG
// iterations; false in `ok` when the result was not finite (the slot is then reset).
int integrate_nodes(HapticSlot& s, HapticScratch& sc, const Vec3& dev, double kc, double ks,
                    double r, const std::array<HapticContact, kHapticMaxContacts>& contacts,
                    uint32_t ncontacts, const HapticSettings& st, bool& ok) {
  ok = true;
  const HapticTool& m = s.model;
  const uint32_t n = m.node_count;
  const double dt = st.dt_s;
  const double damping = std::max(0.0, double(m.damping_mn_s_per_mm));
  const uint32_t grasped = m.grasped_node < n ? m.grasped_node : kHapticMaxNodes;
  bool any = false;
  for (uint32_t i = 0; i < n; ++i) {
    sc.unknown[i] = (m.kind[i] == HapticNodeKind::Free || i == grasped) ? 1 : 0;
    any = any || sc.unknown[i];
  }
  if (!any) return 0;
  accumulate_forces(s, sc, dev, kc, ks, r, contacts, ncontacts, grasped, damping);
  if (st.integrator != NodeIntegrator::SymplecticEuler)
    return backward_euler_step(s, sc, kc, ks, contacts, ncontacts, grasped, damping, st, ok);
  const double* f = sc.rhs.data();
  for (uint32_t i = 0; i < n; ++i) {
    if (!sc.unknown[i] || !(m.mass[i] > 0)) continue;
    const double im = dt / m.mass[i];
    s.vx[i] += im * f[3 * i], s.vy[i] += im * f[3 * i + 1], s.vz[i] += im * f[3 * i + 2];
    s.x[i] += dt * s.vx[i], s.y[i] += dt * s.vy[i], s.z[i] += dt * s.vz[i];
  }
  for (uint32_t i = 0; i < n; ++i) {
    if (!(std::isfinite(s.x[i]) && std::isfinite(s.y[i]) && std::isfinite(s.z[i]) &&
          std::abs(s.x[i]) < 1e6 && std::abs(s.y[i]) < 1e6 && std::abs(s.z[i]) < 1e6)) {
      ok = false;
    }
  }
  return 0;
}

// The tool's side of each new triangle is read from where the simulation had the tool (tip_mm):
// the simulation keeps its tool outside, while the proxy carried over from the previous model may
// already be behind a triangle that moved between the two publishes.
void init_sides(HapticSlot& s, HapticScratch& sc) {
  compute_normals(s, sc);
  const Vec3 tip(s.model.tip_mm[0], s.model.tip_mm[1], s.model.tip_mm[2]);
  const uint32_t nt = std::min(s.model.triangle_count, kHapticMaxTriangles);
  for (uint32_t t = 0; t < nt; ++t) {
    const double sd = sc.tnx[t] * tip.x() + sc.tny[t] * tip.y() + sc.tnz[t] * tip.z() - sc.td[t];
    s.side[t] = sd >= 0 ? 1 : -1;
  }
}

// One tick of one model: contacts, nodes, proxy, force.
void tick_slot(HapticSlot& s, HapticScratch& sc, const Vec3& dev, const Vec3& dev_vel,
               const HapticSettings& st, uint64_t& resets) {
  const HapticTool& m = s.model;
  s.active = 0, s.penetration_mm = 0, s.lens_depth_mm = 0, s.sphere_depth_mm = 0, s.iterations = 0;
  const double dt = st.dt_s;
  if (!m.present) {
    s.proxy_velocity = (dev - s.proxy) / dt;
    s.proxy = dev, s.surface_proxy = dev, s.force = Vec3::Zero(), s.held = {};
    return;
  }
  const double r = std::max(0.0, double(m.tip_radius_mm));
  const double kc = st.coupling_stiffness_mn_per_mm;
  const double kp =
      m.patch_stiffness_mn_per_mm > 0 ? double(m.patch_stiffness_mn_per_mm) : st.rigid_ratio * kc;
  const double ks = kc * kp / (kc + kp);
  const uint32_t grasped = m.grasped_node < m.node_count ? m.grasped_node : kHapticMaxNodes;

  // 1–2. contacts seen from the device, then the local nodes.
  std::array<HapticContact, kHapticMaxContacts> contacts;
  uint32_t nc = 0;
  compute_normals(s, sc);
  gather_contacts(s, sc, dev, r, st, contacts, nc);
  if (m.node_count > 0) {
    bool ok = true;
    s.iterations = integrate_nodes(s, sc, dev, kc, ks, r, contacts, nc, st, ok);
    if (!ok) reset_nodes(s), ++resets;
    compute_normals(s, sc);
  }

  // 3. proxy.
  Vec3 p;
  if (grasped < m.node_count) {
    p = node(s, grasped);
    s.active |= kTermGrasp;
  } else {
    Planes planes;
    uint32_t np = 0;
    nc = 0;
    gather_contacts(s, sc, dev, r, st, contacts, nc);
    const double kf = m.lens_stiffness_mn_per_mm;
    auto build = [&](const Vec3& at) {
      np = 0;
      for (uint32_t c = 0; c < nc; ++c)
        planes[np++] = {contacts[c].normal, contacts[c].point, kp * contacts[c].weight};
      if (m.lens_present && kf > 0) {
        const LensContact lc = lens_penetration(m, at, r);
        if (lc.depth_mm > -r) planes[np++] = {lc.normal, lc.nearest_mm, kf};
      }
    };
    build(dev);
    const uint32_t first_sphere = np;
    if (m.sphere_count > 0) {
      Planes rigid;
      double unused = 0;
      const uint32_t nq = detail::add_sphere_planes(m, s.surface_proxy, dev, r, st.rigid_ratio * kc,
                                                    rigid, 0, unused);
      s.surface_proxy = solve_proxy(dev, s.surface_proxy, kc, r, rigid, nq);
      np =
          detail::add_sphere_planes(m, s.surface_proxy, dev, r, 0.0, planes, np, s.sphere_depth_mm);
    } else {
      s.surface_proxy = dev;
    }
    p = solve_proxy(dev, s.proxy, kc, r, planes, np);
    for (uint32_t j = first_sphere; j < np; ++j) {
      const double pen = r - planes[j].normal.dot(p - planes[j].point);
      if (!(pen > 0)) continue;
      s.active |= kTermSpheres;
      if (planes[j].cap > 0 && planes[j].k * pen >= planes[j].cap * (1 - 1e-9))
        s.active |= kTermCut;
    }
    for (uint32_t c = 0; c < nc; ++c) {
      const double pen = r - contacts[c].normal.dot(p - contacts[c].point);
      if (pen > 0) s.active |= kTermContact, s.penetration_mm = std::max(s.penetration_mm, pen);
    }
    if (m.lens_present && kf > 0) {
      const LensContact lc = lens_penetration(m, p, r);
      if (lc.depth_mm > 0) s.active |= kTermLens, s.lens_depth_mm = lc.depth_mm;
    }
  }

  // 4. virtual coupling.
  s.proxy_velocity = (p - s.proxy) / dt;
  s.proxy = p;
  s.force = -kc * (dev - p) - st.coupling_damping_mn_s_per_mm * (dev_vel - s.proxy_velocity);
  // A held flap tears rather than pull harder than its tear resistance (issue 17 item 5).
  if (grasped < m.node_count && m.grasp_limit_mn > 0) {
    const double mag = s.force.norm(), limit = m.grasp_limit_mn;
    if (mag > limit) s.force *= limit / mag;
  }
  // A held fragment hangs from the proxy (held_load.cpp); its load goes to the hand.
  if (m.held.held) {
    s.force += detail::held_load(m.held, p, s.proxy_velocity, st, s.held);
    s.active |= kTermHeld;
  } else {
    s.held = {};
  }

  // The god-object's memory: a triangle's side changes only when the proxy has gone round it —
  // clear of its plane and beside it (projection outside); over the face, the side it had holds
  // (the proxy cannot have passed through, so a face seen from behind has moved or tilted past it).
  const uint32_t nt = std::min(m.triangle_count, kHapticMaxTriangles);
  for (uint32_t t = 0; t < nt; ++t) {
    if (!sc.tvalid[t]) continue;
    const double sd = sc.tnx[t] * p.x() + sc.tny[t] * p.y() + sc.tnz[t] * p.z() - sc.td[t];
    if (std::abs(sd) <= r + st.contact_margin_mm || (sd > 0) == (s.side[t] > 0)) continue;
    const auto& tri = m.triangles[t];
    std::array<double, 3> w;
    bool inside = false;
    closest_on_triangle(p, node(s, tri[0]), node(s, tri[1]), node(s, tri[2]), w, inside);
    if (!inside) s.side[t] = sd > 0 ? 1 : -1;
  }
}

}  // namespace

LensContact lens_penetration(const HapticTool& tool, const Vec3& p, double radius_mm) {
  LensContact out;
  if (!tool.lens_present) return out.depth_mm = -1e9, out.signed_distance_mm = 1e9, out;
  const Vec3 centre(tool.lens_centre_mm[0], tool.lens_centre_mm[1], tool.lens_centre_mm[2]);
  const Vec3 rel = p - centre;
  const double rho = std::hypot(rel.x(), rel.y()), zz = rel.z();
  const double a = tool.lens_equator_radius_mm;
  const double c_half[2] = {tool.lens_anterior_mm, tool.lens_posterior_mm};
  const double own = zz >= 0 ? c_half[0] : c_half[1];
  const double f = (rho / a) * (rho / a) + (zz / own) * (zz / own);
  const bool inside = f < 1;
  // Far outside: the gap between the surface and its copy scaled by √f is ≥ (√f − 1)·min axis.
  const double bound = (std::sqrt(f) - 1) * std::min({a, c_half[0], c_half[1]});
  if (bound > radius_mm + 1.0) {
    out.signed_distance_mm = bound, out.depth_mm = radius_mm - bound;
    return out;
  }
  const ArcTable& tab = arc_table();
  double best = 1e300, best_t = 0;
  int best_h = 0;
  for (int h = 0; h < 2; ++h) {
    const double c = c_half[h], sg = h == 0 ? 1.0 : -1.0;
    int kbest = 0;
    double dbest = 1e300;
    for (int k = 0; k < kArcSamples; ++k) {
      const double er = rho - a * tab.c[k], ez = zz - sg * c * tab.s[k];
      const double d2 = er * er + ez * ez;
      if (d2 < dbest) dbest = d2, kbest = k;
    }
    // Newton on the arc parameter θ, kept within the scan cell around the best sample.
    const double h_step = kHalfPi / (kArcSamples - 1);
    const double lo = std::max(0.0, (kbest - 1) * h_step),
                 hi = std::min(kHalfPi, (kbest + 1) * h_step);
    double th = kbest * h_step;
    for (int it = 0; it < 8; ++it) {
      const double ct = std::cos(th), st = std::sin(th);
      const double qr = a * ct, qz = sg * c * st;
      const double dr = -a * st, dz = sg * c * ct;  // q'
      const double g = -((rho - qr) * dr + (zz - qz) * dz);
      const double hss = dr * dr + dz * dz - ((rho - qr) * (-qr) + (zz - qz) * (-qz));
      double next = hss > 1e-12 ? th - g / hss : th - 0.1 * h_step * (g > 0 ? 1 : -1);
      next = std::clamp(next, lo, hi);
      if (std::abs(next - th) < 1e-14) break;
      th = next;
    }
    const double er = rho - a * std::cos(th), ez = zz - sg * c * std::sin(th);
    const double refined = er * er + ez * ez;
    const double d2 = std::min(refined, dbest);
    if (d2 < best) best = d2, best_t = refined <= dbest ? th : kbest * h_step, best_h = h;
  }
  const double c = c_half[best_h], sg = best_h == 0 ? 1.0 : -1.0;
  const double qr = a * std::cos(best_t), qz = sg * c * std::sin(best_t);
  const Vec3 e = rho > 1e-12 ? Vec3(rel.x() / rho, rel.y() / rho, 0) : Vec3::UnitX();
  Vec3 n2(qr / (a * a), 0, qz / (c * c));  // outward gradient in the meridian plane
  n2.normalize();
  out.normal = n2.x() * e + Vec3(0, 0, n2.z());
  out.nearest_mm = centre + qr * e + Vec3(0, 0, qz);
  const double dist = std::sqrt(best);
  out.signed_distance_mm = inside ? -dist : dist;
  out.depth_mm = radius_mm - out.signed_distance_mm;
  return out;
}

void adopt_model(const HapticTool& model, HapticToolState& state, const HapticSettings& settings) {
  HapticSlot& cur = state.slot[state.newest];
  const uint8_t target = state.newest ^ 1;
  HapticSlot& next = state.slot[target];
  // A model replaced mid-blend: keep the share it still had as a decaying offset, so the switch
  // itself does not jump.
  if (state.blending && next.live) {
    state.offset =
        state.offset * state.offset_weight + (1.0 - state.blend_weight) * (next.force - cur.force);
    state.offset_weight = 1.0;
  }
  next.model = model;
  if (next.model.node_count > kHapticMaxNodes) next.model.node_count = kHapticMaxNodes;
  if (next.model.triangle_count > kHapticMaxTriangles)
    next.model.triangle_count = kHapticMaxTriangles;
  if (next.model.sphere_count > kHapticMaxSpheres) next.model.sphere_count = kHapticMaxSpheres;
  next.live = true;
  reset_nodes(next);
  const bool carry = cur.live && cur.model.present;
  next.proxy = carry ? cur.proxy : Vec3(model.tip_mm[0], model.tip_mm[1], model.tip_mm[2]);
  next.proxy_velocity = carry ? cur.proxy_velocity : Vec3::Zero();
  next.surface_proxy = carry ? cur.surface_proxy : next.proxy;
  next.force = cur.live ? cur.force : Vec3::Zero();
  // The same fragment still held: it keeps swinging where it was.
  next.held = cur.live && cur.model.held.held && model.held.held ? cur.held : HeldLoadState{};
  init_sides(next, state.scratch);
  if (cur.live && settings.blend_ms > 0) {
    state.blending = true, state.slewing = true, state.blend_weight = 0.0;
  } else {
    state.blending = false, state.blend_weight = 1.0;
    cur.live = false;
  }
  state.newest = target;
  ++state.models_adopted;
}

HapticForce haptic_tick(const HapticTool& model, const Vec3& device_pos_mm,
                        const Vec3& device_vel_mm_s, const HapticSettings& settings,
                        HapticToolState& state) {
  HapticForce out;
  ++state.ticks;
  if (!finite(device_pos_mm) || !finite(device_vel_mm_s)) {
    ++state.inputs_rejected;
    out.input_rejected = true;
    return out;
  }
  const HapticSlot& nw = state.slot[state.newest];
  if (&model != &nw.model &&
      (!nw.live || model.present != nw.model.present || model.node_count != nw.model.node_count ||
       model.triangle_count != nw.model.triangle_count ||
       model.grasped_node != nw.model.grasped_node || model.sphere_count != nw.model.sphere_count ||
       model.held.held != nw.model.held.held)) {
    adopt_model(model, state, settings);
  }
  HapticSlot& cur = state.slot[state.newest];
  HapticSlot& old = state.slot[state.newest ^ 1];
  const Vec3 cur_before = cur.force, old_before = old.force;
  tick_slot(cur, state.scratch, device_pos_mm, device_vel_mm_s, settings, state.slot_resets);
  Vec3 f = cur.force;
  out.active = cur.active;
  double natural = (cur.force - cur_before).norm();  // the model's own change this tick
  const double step = settings.blend_ms > 0 ? settings.dt_s / (settings.blend_ms * 1e-3) : 1.0;
  if (old.live && (state.blending || state.slewing)) {
    // The settled model keeps ticking until the output has caught up: its own change is the
    // natural rate the slew bound allows on top (the new model's first ticks are not).
    tick_slot(old, state.scratch, device_pos_mm, device_vel_mm_s, settings, state.slot_resets);
    natural = (old.force - old_before).norm();
  }
  if (state.blending && old.live) {
    state.blend_weight = std::min(1.0, state.blend_weight + step);
    f = (1.0 - state.blend_weight) * old.force + state.blend_weight * cur.force;
    out.active |= kTermBlend;
    if (state.blend_weight >= 1.0) state.blending = false;
  } else {
    state.blending = false, state.blend_weight = 1.0;
  }
  if (state.offset_weight > 0) {
    f += state.offset_weight * state.offset;
    state.offset_weight = std::max(0.0, state.offset_weight - step);
  }
  // Slew bound while a new model settles in: beyond what the models' own motion changes, the
  // output moves by at most blend_max_step_mn per tick (a new model's first ticks can differ
  // from its predecessor's by more than a linear fade over a few ms would hide).
  if (state.slewing && settings.blend_max_step_mn > 0 && finite(f)) {
    const Vec3 delta = f - state.last_force;
    const double cap = settings.blend_max_step_mn + natural, len = delta.norm();
    if (len > cap) {
      f = state.last_force + delta * (cap / len);
      out.active |= kTermBlend;
    } else if (!state.blending && state.offset_weight <= 0) {
      state.slewing = false;
    }
  }
  if (!state.blending && !state.slewing) old.live = false;
  if (!finite(f)) f = Vec3::Zero();
  const double mag = f.norm();
  if (mag > settings.max_force_mn) {
    f *= settings.max_force_mn / mag;
    out.clamped = true;
    ++state.clamped_ticks;
  }
  state.last_force = f, state.last_device = device_pos_mm, state.has_device = true;
  out.force_mn = f;
  out.proxy_mm = cur.proxy;
  out.penetration_mm = cur.penetration_mm;
  out.lens_depth_mm = cur.lens_depth_mm;
  out.sphere_depth_mm = cur.sphere_depth_mm;
  out.held_load_mn = cur.held.load;
  out.blend_weight = state.blend_weight;
  out.solver_iterations = cur.iterations;
  return out;
}

}  // namespace phaco::haptic_model
