#include "systems/deform/xpbd.hpp"

#include <algorithm>
#include <cmath>

#include "systems/deform/forces.hpp"

namespace phaco::deform {

namespace {

// One constraint projection of the Gauss-Seidel sweep. `d` is the step's scratch: its in_play
// marks are read, its displacements written (one object, one name).
struct Projector {
  const Membrane& m;
  XpbdScratch& d;
  bool restricted;
  float inv_dt2;

  float weight(uint32_t i) const {
    if (restricted && d.in_play[i] == 0) return 0.0f;
    return integrating_inv_mass(m, i);
  }

  // Positions during the solve are x + d: x the start of the step, d the step's displacement.
  void project(uint32_t e, std::vector<float>& lambda) const {
    const Particles& p = m.particles;
    const Springs& s = m.springs;
    const uint32_t i = s.i[e], j = s.j[e];
    const float wi = weight(i), wj = weight(j);
    if (wi + wj <= 0.0f || s.stiffness[e] <= 0.0f) return;
    const float dx = (p.x[j] - p.x[i]) + (d.dx[j] - d.dx[i]);
    const float dy = (p.y[j] - p.y[i]) + (d.dy[j] - d.dy[i]);
    const float dz = (p.z[j] - p.z[i]) + (d.dz[j] - d.dz[i]);
    const float l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (l <= 0.0f) return;
    const float ext = l - s.rest_length[e];
    float c = ext, g = 1.0f;  // constraint value and |∇C| at each end
    if (m.dynamics.law == SpringLaw::Quadratic) {
      constexpr float kRoot2over3 = 0.81649658f;
      const float root = std::sqrt(std::fabs(ext));
      c = kRoot2over3 * ext * root;
      g = 1.5f * kRoot2over3 * root;
    }
    const float alpha = inv_dt2 / s.stiffness[e];
    const float dl = (-c - alpha * lambda[e]) / ((wi + wj) * g * g + alpha);
    lambda[e] += dl;
    const float step = g * dl / l;  // along the unit axis
    d.dx[i] -= wi * step * dx, d.dy[i] -= wi * step * dy, d.dz[i] -= wi * step * dz;
    d.dx[j] += wj * step * dx, d.dy[j] += wj * step * dy, d.dz[j] += wj * step * dz;
  }
};

}  // namespace

Motion xpbd_step(Membrane& m, double dt_s, XpbdScratch& sc) {
  Particles& p = m.particles;
  const uint32_t n = p.slots.size(), ns = m.springs.slots.size();
  if (sc.lambda.size() != ns) sc.lambda.assign(ns, 0.0f);
  if (sc.dx.size() != n) {
    sc.dx.assign(n, 0.0f), sc.dy.assign(n, 0.0f), sc.dz.assign(n, 0.0f);
    sc.glue_lambda.assign(3 * size_t{n}, 0.0f);
    sc.in_play.assign(n, 0);
  }
  const ParticleSet set = particles_in_play(m);
  const bool restricted = !m.active.empty();
  const uint32_t rejected =
      compute_forces(m, ForceTerms{.springs = false, .damping = false, .glue = false});
  const float dt = static_cast<float>(dt_s);
  const float keep = 1.0f / (1.0f + dt * (m.dynamics.damping_per_s + m.dynamics.viscosity_per_s));
  const Forces& f = m.forces;

  parallel_for(0u, set.size(), kParticleGrain, [&](uint32_t begin, uint32_t end, int) {
    for (uint32_t k = begin; k < end; ++k) {
      const uint32_t i = set[k];
      sc.dx[i] = sc.dy[i] = sc.dz[i] = 0.0f;
      sc.glue_lambda[3 * size_t{i}] = sc.glue_lambda[3 * size_t{i} + 1] =
          sc.glue_lambda[3 * size_t{i} + 2] = 0.0f;
      const float w = integrating_inv_mass(m, i);
      if (w <= 0.0f) continue;
      sc.dx[i] = dt * (p.vx[i] + dt * w * f.fx[i]) * keep;
      sc.dy[i] = dt * (p.vy[i] + dt * w * f.fy[i]) * keep;
      sc.dz[i] = dt * (p.vz[i] + dt * w * f.fz[i]) * keep;
    }
  });
  if (restricted) {
    for (const uint32_t i : m.active) sc.in_play[i] = 1;
    for (const uint32_t e : m.active_springs) sc.lambda[e] = 0.0f;
  } else {
    std::fill(sc.lambda.begin(), sc.lambda.end(), 0.0f);
  }

  const Projector proj{m, sc, restricted, 1.0f / (dt * dt)};
  const Glue* glue =
      m.glue && m.dynamics.glue_stiffness_mn_mm > 0.0f && m.glue->x.size() == n ? m.glue : nullptr;
  const float glue_alpha = glue ? 1.0f / (m.dynamics.glue_stiffness_mn_mm * dt * dt) : 0.0f;
  const SpringBlocks& blocks = m.blocks;
  const uint32_t nb = blocks.count();
  for (uint16_t it = 0; it < sc.iterations; ++it) {
    if (restricted) {
      for (const uint32_t e : m.active_springs) proj.project(e, sc.lambda);
    } else if (nb <= 2) {
      for (uint32_t e = 0; e < ns; ++e) proj.project(e, sc.lambda);
    } else {
      for (uint32_t parity = 0; parity < 2; ++parity) {
        parallel_for(0u, (nb - parity + 1) / 2, 1, [&](uint32_t begin, uint32_t end, int) {
          for (uint32_t k = begin; k < end; ++k) {
            const uint32_t b = 2 * k + parity;
            for (uint32_t e = blocks.spring_begin[b]; e < blocks.spring_begin[b + 1]; ++e)
              proj.project(e, sc.lambda);
          }
        });
      }
      for (uint32_t e = blocks.tail_begin(); e < ns; ++e) proj.project(e, sc.lambda);
    }
    if (!glue) continue;
    parallel_for(0u, set.size(), kParticleGrain, [&](uint32_t begin, uint32_t end, int) {
      for (uint32_t k = begin; k < end; ++k) {
        const uint32_t i = set[k];
        const float w = integrating_inv_mass(m, i);
        if (w <= 0.0f) continue;
        float* lam = &sc.glue_lambda[3 * size_t{i}];
        float* disp[3] = {&sc.dx[i], &sc.dy[i], &sc.dz[i]};
        const float off[3] = {p.x[i] - glue->x[i], p.y[i] - glue->y[i], p.z[i] - glue->z[i]};
        for (int a = 0; a < 3; ++a) {
          const float dl = (-(off[a] + *disp[a]) - glue_alpha * lam[a]) / (w + glue_alpha);
          lam[a] += dl;
          *disp[a] += w * dl;
        }
      }
    });
  }
  if (restricted) {
    for (const uint32_t i : m.active) sc.in_play[i] = 0;
  }

  const float inv_dt = 1.0f / dt, limit2 = speed_limit2(m);
  Motion motion = for_each_in_play(set, [&](uint32_t i, ChunkMotion& local) {
    if (integrating_inv_mass(m, i) <= 0.0f) return;
    p.vx[i] = sc.dx[i] * inv_dt, p.vy[i] = sc.dy[i] * inv_dt, p.vz[i] = sc.dz[i] * inv_dt;
    p.x[i] += sc.dx[i], p.y[i] += sc.dy[i], p.z[i] += sc.dz[i];
    observe(local, true, p.x[i], p.y[i], p.z[i], p.vx[i], p.vy[i], p.vz[i], limit2);
  });
  motion.rejected_loads = rejected;
  return motion;
}

}  // namespace phaco::deform
