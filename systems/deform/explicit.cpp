#include "systems/deform/explicit.hpp"

#include <algorithm>
#include <cmath>

#include "systems/deform/forces.hpp"
#include "systems/deform/spring_law.hpp"

namespace phaco::deform {

namespace {

inline void add_axial(const Membrane& m, uint32_t e, std::vector<float>& kappa) {
  const Springs& s = m.springs;
  const Particles& p = m.particles;
  const uint32_t i = s.i[e], j = s.j[e];
  float k = s.stiffness[e];
  if (m.dynamics.law == SpringLaw::Quadratic) {
    const float dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i], dz = p.z[j] - p.z[i];
    k = spring_axial_stiffness(SpringLaw::Quadratic, k,
                               std::sqrt(dx * dx + dy * dy + dz * dz) - s.rest_length[e]);
  }
  kappa[i] += k;
  kappa[j] += k;
}

// The whole-body paths of the two explicit steps, on restrict pointers so the compiler can
// vectorise them (particles is SoA; a lambda over std::vector references stays scalar: the
// compiler cannot prove x, v and f do not alias). `symplectic` picks the order of the updates.
template <bool kSymplectic>
ChunkMotion explicit_chunk(uint32_t begin, uint32_t end, float dt, float inv_scale, float limit2,
                           float* __restrict x, float* __restrict y, float* __restrict z,
                           float* __restrict vx, float* __restrict vy, float* __restrict vz,
                           const float* __restrict fx, const float* __restrict fy,
                           const float* __restrict fz, const float* __restrict inv_mass,
                           const ParticleKind* __restrict kind) {
  float max2 = 0.0f;
  uint32_t bad = 0;
  for (uint32_t i = begin; i < end; ++i) {
    const bool moved = kind[i] == ParticleKind::Free;
    const float w = moved ? inv_mass[i] * inv_scale : 0.0f;
    const float h =
        moved ? dt : 0.0f;  // scripted particles keep their imposed velocity and stay put
    const float nvx = vx[i] + dt * w * fx[i], nvy = vy[i] + dt * w * fy[i],
                nvz = vz[i] + dt * w * fz[i];
    const float ux = kSymplectic ? nvx : vx[i], uy = kSymplectic ? nvy : vy[i],
                uz = kSymplectic ? nvz : vz[i];
    x[i] += h * ux, y[i] += h * uy, z[i] += h * uz;
    vx[i] = nvx, vy[i] = nvy, vz[i] = nvz;
    // observe() written out on locals, which the vectoriser handles.
    const float s2 = nvx * nvx + nvy * nvy + nvz * nvz;
    const bool ok =
        (s2 <= limit2) & (x[i] - x[i] == 0.0f) & (y[i] - y[i] == 0.0f) & (z[i] - z[i] == 0.0f);
    bad += static_cast<uint32_t>(moved & !ok);
    const float seen = (moved & ok) ? s2 : 0.0f;
    max2 = max2 > seen ? max2 : seen;
  }
  return {max2, bad};
}

template <bool kSymplectic>
Motion explicit_whole_body(Membrane& m, float dt) {
  Particles& p = m.particles;
  const Forces& f = m.forces;
  const float limit2 = speed_limit2(m), inv_scale = inverse_mass_scale(m.dynamics);
  const ChunkMotion total = parallel_reduce_ordered(
      0u, p.slots.size(), kParticleGrain, ChunkMotion{},
      [&](uint32_t begin, uint32_t end) {
        return explicit_chunk<kSymplectic>(begin, end, dt, inv_scale, limit2, p.x.data(),
                                           p.y.data(), p.z.data(), p.vx.data(), p.vy.data(),
                                           p.vz.data(), f.fx.data(), f.fy.data(), f.fz.data(),
                                           p.inv_mass.data(), p.kind.data());
      },
      [](ChunkMotion a, const ChunkMotion& b) {
        a.max_speed2 = a.max_speed2 > b.max_speed2 ? a.max_speed2 : b.max_speed2;
        a.bad += b.bad;
        return a;
      });
  return {std::sqrt(total.max_speed2), total.bad, 0};
}

}  // namespace

void sum_axial_stiffness(const Membrane& m, std::vector<float>& kappa) {
  const uint32_t n = m.particles.slots.size();
  if (kappa.size() != n) kappa.assign(n, 0.0f);
  const float glue =
      m.glue && m.dynamics.glue_stiffness_mn_mm > 0.0f ? m.dynamics.glue_stiffness_mn_mm : 0.0f;
  if (m.active.empty()) {
    std::fill(kappa.begin(), kappa.end(), glue);
    const SpringBlocks& blocks = m.blocks;
    const uint32_t nb = blocks.count();
    if (nb <= 2) {
      for (uint32_t e = 0; e < m.springs.slots.size(); ++e) add_axial(m, e, kappa);
      return;
    }
    // Same even/odd block order as springs::add_spring_forces: blocks of one parity share no
    // particle.
    for (uint32_t parity = 0; parity < 2; ++parity) {
      parallel_for(0u, (nb - parity + 1) / 2, 1, [&](uint32_t begin, uint32_t end, int) {
        for (uint32_t k = begin; k < end; ++k) {
          const uint32_t b = 2 * k + parity;
          for (uint32_t e = blocks.spring_begin[b]; e < blocks.spring_begin[b + 1]; ++e)
            add_axial(m, e, kappa);
        }
      });
    }
    for (uint32_t e = blocks.tail_begin(); e < m.springs.slots.size(); ++e) add_axial(m, e, kappa);
    return;
  }
  for (const uint32_t i : m.active) kappa[i] = glue;
  for (const uint32_t e : m.active_springs) kappa[m.springs.i[e]] = kappa[m.springs.j[e]] = glue;
  for (const uint32_t e : m.active_springs) add_axial(m, e, kappa);
}

namespace {

// Explicit and symplectic Euler differ only in whether the velocity is updated before the
// position moves with it; one loop serves both, over the whole body or the active set.
template <bool kSymplectic>
Motion euler_step(Membrane& m, double dt_s) {
  const uint32_t rejected = compute_forces(m);
  if (m.active.empty()) {
    Motion motion = explicit_whole_body<kSymplectic>(m, static_cast<float>(dt_s));
    motion.rejected_loads = rejected;
    return motion;
  }
  Particles& p = m.particles;
  const Forces& f = m.forces;
  const float dt = static_cast<float>(dt_s), limit2 = speed_limit2(m),
              inv_scale = inverse_mass_scale(m.dynamics);
  Motion motion = for_each_in_play(particles_in_play(m), [&](uint32_t i, ChunkMotion& local) {
    const float w = integrating_inv_mass(p, i, inv_scale);
    const float h =
        w > 0.0f ? dt : 0.0f;  // scripted particles keep their imposed velocity and stay put
    if constexpr (!kSymplectic) p.x[i] += h * p.vx[i], p.y[i] += h * p.vy[i], p.z[i] += h * p.vz[i];
    p.vx[i] += dt * w * f.fx[i], p.vy[i] += dt * w * f.fy[i], p.vz[i] += dt * w * f.fz[i];
    if constexpr (kSymplectic) p.x[i] += h * p.vx[i], p.y[i] += h * p.vy[i], p.z[i] += h * p.vz[i];
    observe(local, w > 0.0f, p.x[i], p.y[i], p.z[i], p.vx[i], p.vy[i], p.vz[i], limit2);
  });
  motion.rejected_loads = rejected;
  return motion;
}

}  // namespace

Motion explicit_euler_step(Membrane& m, double dt_s) {
  return euler_step<false>(m, dt_s);
}

Motion symplectic_euler_step(Membrane& m, double dt_s) {
  return euler_step<true>(m, dt_s);
}

Motion semi_implicit_001_step(Membrane& m, double dt_s, std::vector<float>& kappa) {
  const uint32_t rejected = compute_forces(m);
  sum_axial_stiffness(m, kappa);
  Particles& p = m.particles;
  const Forces& f = m.forces;
  const float dt = static_cast<float>(dt_s), limit2 = speed_limit2(m),
              inv_scale = inverse_mass_scale(m.dynamics);
  const float keep = 1.0f + dt * (m.dynamics.damping_per_s + m.dynamics.viscosity_per_s);
  Motion motion = for_each_in_play(particles_in_play(m), [&](uint32_t i, ChunkMotion& local) {
    const float w = integrating_inv_mass(p, i, inv_scale);
    if (w <= 0.0f) return;  // the division below must not touch a scripted particle's velocity
    const float inv_diag = 1.0f / (keep + dt * dt * kappa[i] * w);
    p.vx[i] = (keep * p.vx[i] + dt * w * f.fx[i]) * inv_diag;
    p.vy[i] = (keep * p.vy[i] + dt * w * f.fy[i]) * inv_diag;
    p.vz[i] = (keep * p.vz[i] + dt * w * f.fz[i]) * inv_diag;
    p.x[i] += dt * p.vx[i], p.y[i] += dt * p.vy[i], p.z[i] += dt * p.vz[i];
    observe(local, true, p.x[i], p.y[i], p.z[i], p.vx[i], p.vy[i], p.vz[i], limit2);
  });
  motion.rejected_loads = rejected;
  return motion;
}

}  // namespace phaco::deform
