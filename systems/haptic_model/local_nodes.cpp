// The local nodes' step; see local_nodes.hpp.
#include "systems/haptic_model/local_nodes.hpp"

#include <algorithm>
#include <cmath>

namespace phaco::haptic_model::detail {
namespace {

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

}  // namespace

void reset_nodes(HapticSlot& s) {
  const HapticTool& m = s.model;
  for (uint32_t i = 0; i < m.node_count; ++i) {
    s.x[i] = m.x[i], s.y[i] = m.y[i], s.z[i] = m.z[i];
    s.vx[i] = m.vx[i], s.vy[i] = m.vy[i], s.vz[i] = m.vz[i];
  }
  std::fill(s.warm_dv.begin(), s.warm_dv.end(), 0.0);
}

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

}  // namespace phaco::haptic_model::detail
