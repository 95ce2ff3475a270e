// Seed 004's approximate implicit predictor (Desbrun, Schröder & Barr 1999); see implicit.hpp.
//
// What is precomputed, once per (dt, masses, particle kinds, damping, glue, springs):
//   the frozen spring blocks H_e (Isotropic: k_e·I with k_e = k for the linear law and
//   2k·max(|l − l0|, ext_ref) for the quadratic one; FrozenJacobian: spring_force_jacobian at
//   the current shape), and the LDLᵀ factorisation (AMD ordering) of
//     A_uu = m_u·(1 + dt·(γ + κ))·I + dt²·(g·I + Σ_e∋u H_e),   A_uw = −dt²·H_e,
//   scalar n×n for Isotropic (one factor, three right sides), 3n×3n for FrozenJacobian.
// What every step does: one pass over the springs for the exact force and the frozen H·v term,
// one forward/backward substitution, and the line search.
#include <algorithm>
#include <bit>
#include <cmath>
#include <stdexcept>

#include "systems/deform/implicit.hpp"

namespace phaco::deform {

namespace {

struct Fnv {
  uint64_t h = 1469598103934665603ull;
  void add(uint64_t v) {
    for (int b = 0; b < 8; ++b) h = (h ^ ((v >> (8 * b)) & 0xffu)) * 1099511628211ull;
  }
  void add(double v) { add(std::bit_cast<uint64_t>(v)); }
};

inline double sym_at(const Sym3& k, int a, int b) {
  static constexpr int kIndex[3][3] = {{0, 1, 2}, {1, 3, 4}, {2, 4, 5}};
  return k[kIndex[a][b]];
}

bool is_unknown_kind(const Particles& p, uint32_t i) {
  return p.slots.alive(i) && p.kind[i] == ParticleKind::Free && p.inv_mass[i] > 0.0f;
}

// Everything the factorisation depends on except spring stiffness and rest length values, which
// change only with topology or material (invalidate()).
uint64_t predictor_key(const Membrane& m, double dt, const ImplicitCache& c) {
  const Particles& p = m.particles;
  const Dynamics& d = m.dynamics;
  Fnv f;
  f.add(dt);
  f.add(implicit_detail::mass_scale(d));
  f.add(double(d.damping_per_s) + d.viscosity_per_s);
  f.add(m.glue && m.glue->x.size() == p.slots.size() ? double(d.glue_stiffness_mn_mm) : 0.0);
  f.add(uint64_t(d.law));
  f.add(c.settings.predictor_quadratic_extension_mm);
  f.add(uint64_t(c.settings.predictor_stiffness));
  f.add(uint64_t(m.springs.slots.size()));
  f.add(uint64_t(p.slots.size()));
  for (uint32_t i = 0; i < p.slots.size(); ++i)
    f.add((uint64_t(is_unknown_kind(p, i)) << 32) | std::bit_cast<uint32_t>(p.inv_mass[i]));
  return f.h;
}

void precompute(const Membrane& m, double dt, ImplicitCache& c) {
  const Particles& p = m.particles;
  const Springs& s = m.springs;
  const Dynamics& d = m.dynamics;
  const uint32_t n = p.slots.size();
  const bool isotropic = c.settings.predictor_stiffness == PredictorStiffness::Isotropic;
  c.predictor_unknown_of.assign(n, kNotUnknown);
  c.predictor_unknowns.clear();
  for (uint32_t i = 0; i < n; ++i) {
    if (!is_unknown_kind(p, i)) continue;
    c.predictor_unknown_of[i] = static_cast<uint32_t>(c.predictor_unknowns.size());
    c.predictor_unknowns.push_back(i);
  }
  const size_t nu = c.predictor_unknowns.size();
  const double dt2 = dt * dt, drag = double(d.damping_per_s) + d.viscosity_per_s;
  const double glue_k = m.glue && m.glue->x.size() == n ? double(d.glue_stiffness_mn_mm) : 0.0;

  c.predictor_springs.clear();
  c.predictor_k.clear();
  std::vector<Sym3> diag(nu);
  for (size_t u = 0; u < nu; ++u) {
    const double m_u =
        implicit_detail::mass_scale(d) / p.inv_mass[c.predictor_unknowns[u]] * (1.0 + dt * drag) +
        dt2 * glue_k;
    diag[u] = {m_u, 0.0, 0.0, m_u, 0.0, m_u};
  }
  std::vector<Eigen::Triplet<double>> triplets;
  for (uint32_t e = 0; e < s.slots.size(); ++e) {
    if (!s.slots.alive(e)) continue;
    const uint32_t i = s.i[e], j = s.j[e];
    const uint32_t ui = c.predictor_unknown_of[i], uj = c.predictor_unknown_of[j];
    if (ui == kNotUnknown && uj == kNotUnknown) continue;
    const double dx = double(p.x[j]) - p.x[i], dy = double(p.y[j]) - p.y[i],
                 dz = double(p.z[j]) - p.z[i];
    Sym3 h;
    if (isotropic) {
      double k = s.stiffness[e];
      if (d.law == SpringLaw::Quadratic) {
        const double ext = std::fabs(std::sqrt(dx * dx + dy * dy + dz * dz) - s.rest_length[e]);
        k = 2.0 * k * std::max(ext, c.settings.predictor_quadratic_extension_mm);
      }
      h = {k, 0.0, 0.0, k, 0.0, k};
    } else {
      h = spring_force_jacobian(dx, dy, dz, s.rest_length[e], s.stiffness[e], d.law).k;
    }
    c.predictor_springs.push_back(e);
    c.predictor_k.push_back(h);
    for (int q = 0; q < 6; ++q) {
      if (ui != kNotUnknown) diag[ui][q] += dt2 * h[q];
      if (uj != kNotUnknown) diag[uj][q] += dt2 * h[q];
    }
    if (ui == kNotUnknown || uj == kNotUnknown) continue;
    if (isotropic) {
      triplets.emplace_back(int(ui), int(uj), -dt2 * h[0]);
      triplets.emplace_back(int(uj), int(ui), -dt2 * h[0]);
      continue;
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b) {
        triplets.emplace_back(int(3 * ui + a), int(3 * uj + b), -dt2 * sym_at(h, a, b));
        triplets.emplace_back(int(3 * uj + a), int(3 * ui + b), -dt2 * sym_at(h, a, b));
      }
  }
  for (size_t u = 0; u < nu; ++u) {
    if (isotropic) {
      triplets.emplace_back(int(u), int(u), diag[u][0]);
      continue;
    }
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        triplets.emplace_back(int(3 * u + a), int(3 * u + b), sym_at(diag[u], a, b));
  }
  const Eigen::Index size = static_cast<Eigen::Index>(isotropic ? nu : 3 * nu);
  Eigen::SparseMatrix<double> a(size, size);
  a.setFromTriplets(triplets.begin(), triplets.end());
  if (nu > 0) {
    c.predictor_factor->compute(a);
    if (c.predictor_factor->info() != Eigen::Success)
      throw std::runtime_error(
          "implicit predictor: the frozen system is not positive definite (check masses)");
  }
  c.predictor_force.resize(static_cast<Eigen::Index>(3 * nu));
  c.predictor_rhs.resize(static_cast<Eigen::Index>(3 * nu));
  c.predictor_dv.resize(static_cast<Eigen::Index>(3 * nu));
  c.stats.predictor_unknowns = static_cast<uint32_t>(nu);
  ++c.stats.precomputations;
}

// Velocity of particle i in the H·v term: its own for an unknown; zero for a fixed particle, which
// does not move during the step (a scripted one is already at its end-of-frame position).
void filter_velocity(const Particles& p, uint32_t i, bool unknown, double v[3]) {
  v[0] = unknown ? p.vx[i] : 0.0, v[1] = unknown ? p.vy[i] : 0.0, v[2] = unknown ? p.vz[i] : 0.0;
}

}  // namespace

void implicit_predictor_step(Membrane& m, double dt, ImplicitCache& c) {
  Particles& p = m.particles;
  const Springs& s = m.springs;
  const Dynamics& d = m.dynamics;
  const uint32_t n = p.slots.size();
  const uint64_t key = predictor_key(m, dt, c);
  if (!c.predictor_valid || key != c.predictor_key) {
    precompute(m, dt, c);
    c.predictor_key = key;
    c.predictor_valid = true;
  }
  ++c.stats.predictor_steps;
  const size_t nu = c.predictor_unknowns.size();
  if (nu == 0) return;

  const double dt2 = dt * dt, drag = double(d.damping_per_s) + d.viscosity_per_s;
  const bool glued = m.glue && m.glue->x.size() == n;
  const double glue_k = glued ? double(d.glue_stiffness_mn_mm) : 0.0;
  Eigen::VectorXd& f = c.predictor_force;
  Eigen::VectorXd& hv = c.predictor_rhs;  // (H + g·I)·v first, then the right side
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = c.predictor_unknowns[u];
    const double true_mass = 1.0 / p.inv_mass[i];
    const double mass = implicit_detail::mass_scale(d) * true_mass;
    const double v[3] = {p.vx[i], p.vy[i], p.vz[i]}, x[3] = {p.x[i], p.y[i], p.z[i]};
    for (int a = 0; a < 3; ++a) {
      const double rest = glued ? (a == 0   ? m.glue->x[i]
                                   : a == 1 ? m.glue->y[i]
                                            : m.glue->z[i])
                                : x[a];
      f[3 * u + a] = true_mass * d.gravity_mm_s2[a] - mass * drag * v[a] - glue_k * (x[a] - rest);
      hv[3 * u + a] = glue_k * v[a];
    }
  }
  implicit_detail::add_point_loads(m, c.predictor_unknown_of, f.data());
  for (size_t t = 0; t < c.predictor_springs.size(); ++t) {
    const uint32_t e = c.predictor_springs[t], i = s.i[e], j = s.j[e];
    const uint32_t ui = c.predictor_unknown_of[i], uj = c.predictor_unknown_of[j];
    const double dx = double(p.x[j]) - p.x[i], dy = double(p.y[j]) - p.y[i],
                 dz = double(p.z[j]) - p.z[i];
    const double l = std::sqrt(dx * dx + dy * dy + dz * dz);
    double fi[3] = {0.0, 0.0, 0.0};
    if (l > 0.0) {
      const double ext = l - s.rest_length[e];
      const double mag =
          d.law == SpringLaw::Linear ? s.stiffness[e] * ext : s.stiffness[e] * ext * std::fabs(ext);
      fi[0] = mag * dx / l, fi[1] = mag * dy / l, fi[2] = mag * dz / l;
    }
    double vi[3], vj[3];
    filter_velocity(p, i, ui != kNotUnknown, vi);
    filter_velocity(p, j, uj != kNotUnknown, vj);
    const Sym3& h = c.predictor_k[t];
    const double w[3] = {vi[0] - vj[0], vi[1] - vj[1], vi[2] - vj[2]};
    const double hw[3] = {h[0] * w[0] + h[1] * w[1] + h[2] * w[2],
                          h[1] * w[0] + h[3] * w[1] + h[4] * w[2],
                          h[2] * w[0] + h[4] * w[1] + h[5] * w[2]};
    for (int a = 0; a < 3; ++a) {
      if (ui != kNotUnknown) f[3 * ui + a] += fi[a], hv[3 * ui + a] += hw[a];
      if (uj != kNotUnknown) f[3 * uj + a] -= fi[a], hv[3 * uj + a] -= hw[a];
    }
  }
  hv = dt * f - dt2 * hv;
  if (c.settings.predictor_stiffness == PredictorStiffness::Isotropic) {
    using Columns = Eigen::Matrix<double, Eigen::Dynamic, 3, Eigen::RowMajor>;
    const Eigen::Index rows = static_cast<Eigen::Index>(nu);
    Eigen::Map<Columns>(c.predictor_dv.data(), rows, 3) =
        c.predictor_factor->solve(Eigen::Map<const Columns>(hv.data(), rows, 3));
  } else {
    c.predictor_dv = c.predictor_factor->solve(hv);
  }

  // Δx = dt·(v + Δv); particles outside an active set do not move.
  c.predictor_dx.resize(static_cast<Eigen::Index>(3 * nu));
  const bool restricted = !m.active.empty();
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = c.predictor_unknowns[u];
    const bool moves = !restricted || std::binary_search(m.active.begin(), m.active.end(), i);
    const double v[3] = {p.vx[i], p.vy[i], p.vz[i]};
    for (int a = 0; a < 3; ++a)
      c.predictor_dx[3 * u + a] = moves ? dt * (v[a] + c.predictor_dv[3 * u + a]) : 0.0;
  }
  const double alpha = implicit_detail::line_search(m, dt, c.settings.max_line_search_halvings,
                                                    c.predictor_unknowns, c.predictor_unknown_of,
                                                    c.predictor_springs, c.predictor_dx.data());
  c.stats.step_fraction = alpha;
  if (alpha < 1.0) ++c.stats.line_search_cuts;

  if (m.forces.fx.size() != n) m.forces.resize_zero(n);
  for (size_t u = 0; u < nu; ++u) {
    const uint32_t i = c.predictor_unknowns[u];
    if (restricted && !std::binary_search(m.active.begin(), m.active.end(), i)) continue;
    const double dx = alpha * c.predictor_dx[3 * u], dy = alpha * c.predictor_dx[3 * u + 1],
                 dz = alpha * c.predictor_dx[3 * u + 2];
    p.vx[i] = static_cast<float>(dx / dt), p.vy[i] = static_cast<float>(dy / dt),
    p.vz[i] = static_cast<float>(dz / dt);
    p.x[i] = static_cast<float>(p.x[i] + dx);
    p.y[i] = static_cast<float>(p.y[i] + dy);
    p.z[i] = static_cast<float>(p.z[i] + dz);
    m.forces.fx[i] = static_cast<float>(f[3 * u]);
    m.forces.fy[i] = static_cast<float>(f[3 * u + 1]);
    m.forces.fz[i] = static_cast<float>(f[3 * u + 2]);
  }
}

}  // namespace phaco::deform
