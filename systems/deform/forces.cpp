#include "systems/deform/forces.hpp"

#include <algorithm>
#include <cassert>
#include <cmath>

#include "engine/core/invariants.hpp"
#include "systems/deform/particle_set.hpp"
#include "systems/deform/spring_law.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::deform {

void add_spring_forces_listed(const Membrane& m, std::span<const uint32_t> springs_in_play,
                              Forces& f) {
  const Springs& s = m.springs;
  const Particles& p = m.particles;
  const SpringLaw law = m.dynamics.law;
  for (const uint32_t e : springs_in_play) {
    const uint32_t i = s.i[e], j = s.j[e];
    const float dx = p.x[j] - p.x[i], dy = p.y[j] - p.y[i], dz = p.z[j] - p.z[i];
    const float l = std::sqrt(dx * dx + dy * dy + dz * dz);
    if (l <= 0.0f) continue;  // coincident ends: no direction, no force
    const float scale = spring_magnitude(law, s.stiffness[e], l - s.rest_length[e]) / l;
    const float fx = scale * dx, fy = scale * dy, fz = scale * dz;
    f.fx[i] += fx, f.fy[i] += fy, f.fz[i] += fz;
    f.fx[j] -= fx, f.fy[j] -= fy, f.fz[j] -= fz;
  }
}

uint32_t compute_forces(Membrane& m, ForceTerms terms) {
  const Particles& p = m.particles;
  const uint32_t n = p.slots.size();
  Forces& f = m.forces;
  // What a cut or a compaction leaves must name particles and springs that exist: the springs'
  // ends, the blocks' ranges and the active lists (an index past them is read without a check).
  assert(live_all_below(m.springs.slots, {m.springs.i, m.springs.j}, n));
  assert(m.blocks.particle_begin.empty() || m.blocks.particle_begin.back() <= n);
  assert(m.blocks.tail_begin() <= m.springs.slots.size());
  assert(all_below(m.active, n) && all_below(m.active_springs, m.springs.slots.size()));
  if (f.fx.size() != n || f.fy.size() != n || f.fz.size() != n) f.resize_zero(n);  // first use only
  const ParticleSet set = particles_in_play(m);
  const bool restricted = !m.active.empty();

  if (!restricted) {
    std::fill(f.fx.begin(), f.fx.end(), 0.0f);
    std::fill(f.fy.begin(), f.fy.end(), 0.0f);
    std::fill(f.fz.begin(), f.fz.end(), 0.0f);
    if (terms.springs) springs::add_spring_forces(m.springs, m.blocks, m.dynamics.law, p, f);
  } else {
    for (const uint32_t i : m.active) f.fx[i] = f.fy[i] = f.fz[i] = 0.0f;
    for (const uint32_t e : m.active_springs) {
      const uint32_t i = m.springs.i[e], j = m.springs.j[e];
      f.fx[i] = f.fy[i] = f.fz[i] = 0.0f;
      f.fx[j] = f.fy[j] = f.fz[j] = 0.0f;
    }
    for (const PointLoad& load : m.loads) {
      if (load.particle < n) f.fx[load.particle] = f.fy[load.particle] = f.fz[load.particle] = 0.0f;
    }
    if (terms.springs) add_spring_forces_listed(m, m.active_springs, f);
  }

  const Dynamics& d = m.dynamics;
  const float scale = d.mass_scale > 0.0f ? d.mass_scale : 1.0f;
  const float rate = terms.damping ? d.damping_per_s + d.viscosity_per_s : 0.0f;
  const float gx = d.gravity_mm_s2[0], gy = d.gravity_mm_s2[1], gz = d.gravity_mm_s2[2];
  const Glue* glue = terms.glue && m.glue && d.glue_stiffness_mn_mm > 0.0f && m.glue->x.size() == n
                         ? m.glue
                         : nullptr;
  const float kg = d.glue_stiffness_mn_mm;
  const auto body_forces = [&](uint32_t i) {
    const float inv = p.inv_mass[i];
    const float mass = inv > 0.0f ? 1.0f / inv : 0.0f;  // kg; anchored particles have none
    const float drag = mass * scale * rate;
    // mN/kg = mm/s², so m·g with g in mm/s² is in mN.
    f.fx[i] += mass * gx - drag * p.vx[i];
    f.fy[i] += mass * gy - drag * p.vy[i];
    f.fz[i] += mass * gz - drag * p.vz[i];
    if (glue) {
      f.fx[i] -= kg * (p.x[i] - glue->x[i]);
      f.fy[i] -= kg * (p.y[i] - glue->y[i]);
      f.fz[i] -= kg * (p.z[i] - glue->z[i]);
    }
  };
  parallel_for(0u, set.size(), kParticleGrain, [&](uint32_t begin, uint32_t end, int) {
    if (set.list.empty()) {
      for (uint32_t i = begin; i < end; ++i) body_forces(i);
    } else {
      for (uint32_t k = begin; k < end; ++k) body_forces(set.list[k]);
    }
  });

  uint32_t rejected = 0;
  for (const PointLoad& load : m.loads) {
    if (load.particle >= n || !std::isfinite(load.fx) || !std::isfinite(load.fy) ||
        !std::isfinite(load.fz)) {
      ++rejected;
      continue;
    }
    f.fx[load.particle] += load.fx;
    f.fy[load.particle] += load.fy;
    f.fz[load.particle] += load.fz;
  }
  return rejected;
}

}  // namespace phaco::deform
