#include "systems/deform/guard.hpp"

#include <cmath>

#include "systems/deform/particle_set.hpp"
#include "systems/deform/spring_law.hpp"

namespace phaco::deform {

namespace {

constexpr uint32_t kSpringGrain = 4096;

double spring_energy_of(const Membrane& m, uint32_t e) {
  const Springs& s = m.springs;
  const Particles& p = m.particles;
  const uint32_t i = s.i[e], j = s.j[e];
  const double dx = double{p.x[j]} - p.x[i], dy = double{p.y[j]} - p.y[i],
               dz = double{p.z[j]} - p.z[i];
  return spring_potential(m.dynamics.law, s.stiffness[e],
                          std::sqrt(dx * dx + dy * dy + dz * dz) - s.rest_length[e]);
}

bool finite3(float a, float b, float c) {
  return std::isfinite(a) && std::isfinite(b) && std::isfinite(c);
}

}  // namespace

Energy measure_energy(const Membrane& m) {
  const Particles& p = m.particles;
  const Dynamics& d = m.dynamics;
  const uint32_t n = p.slots.size();
  const double scale = d.mass_scale > 0.0f ? d.mass_scale : 1.0f;
  const Glue* glue =
      m.glue && d.glue_stiffness_mn_mm > 0.0f && m.glue->x.size() == n ? m.glue : nullptr;
  const ParticleSet set = particles_in_play(m);
  const auto add = [](Energy a, const Energy& b) {
    a.kinetic += b.kinetic, a.elastic += b.elastic, a.glue += b.glue, a.potential += b.potential;
    return a;
  };
  Energy e = parallel_reduce_ordered(
      0u, set.size(), kParticleGrain, Energy{},
      [&](uint32_t begin, uint32_t end) {
        Energy part;
        for (uint32_t k = begin; k < end; ++k) {
          const uint32_t i = set[k];
          if (p.kind[i] != ParticleKind::Free || p.inv_mass[i] <= 0.0f) continue;
          const double mass = 1.0 / p.inv_mass[i];
          const double v2 =
              double{p.vx[i]} * p.vx[i] + double{p.vy[i]} * p.vy[i] + double{p.vz[i]} * p.vz[i];
          part.kinetic += 0.5 * mass * scale * v2;
          part.potential -=
              mass * (d.gravity_mm_s2[0] * double{p.x[i]} + d.gravity_mm_s2[1] * double{p.y[i]} +
                      d.gravity_mm_s2[2] * double{p.z[i]});
          if (glue) {
            const double gx = double{p.x[i]} - glue->x[i], gy = double{p.y[i]} - glue->y[i],
                         gz = double{p.z[i]} - glue->z[i];
            part.glue += 0.5 * d.glue_stiffness_mn_mm * (gx * gx + gy * gy + gz * gz);
          }
        }
        return part;
      },
      add);
  if (m.active.empty()) {
    e.elastic = parallel_reduce_ordered(
        0u, m.springs.slots.size(), kSpringGrain, 0.0,
        [&](uint32_t begin, uint32_t end) {
          double sum = 0.0;
          for (uint32_t s = begin; s < end; ++s) sum += spring_energy_of(m, s);
          return sum;
        },
        [](double a, double b) { return a + b; });
  } else {
    for (const uint32_t s : m.active_springs) e.elastic += spring_energy_of(m, s);
  }
  for (const PointLoad& load : m.loads) {
    if (load.particle >= n || !finite3(load.fx, load.fy, load.fz)) continue;
    e.potential -= double{load.fx} * p.x[load.particle] + double{load.fy} * p.y[load.particle] +
                   double{load.fz} * p.z[load.particle];
  }
  return e;
}

bool energy_diverged(const Energy& before, const Energy& after, const EnergyBound& bound) {
  const double gained = after.total() - before.total();
  if (!std::isfinite(gained)) return true;
  const double work = std::fabs(after.potential - before.potential);
  return gained > bound.growth * (before.stored() + work) + bound.floor_uj;
}

void restore_state(Membrane& m, const Snapshot& snap) {
  Particles& p = m.particles;
  if (snap.x.size() != p.slots.size()) return;
  const ParticleSet set = particles_in_play(m);
  parallel_for(0u, set.size(), kParticleGrain, [&](uint32_t begin, uint32_t end, int) {
    for (uint32_t k = begin; k < end; ++k) {
      const uint32_t i = set[k];
      p.x[i] = snap.x[i], p.y[i] = snap.y[i], p.z[i] = snap.z[i];
      p.vx[i] = snap.vx[i], p.vy[i] = snap.vy[i], p.vz[i] = snap.vz[i];
    }
  });
}

namespace {

bool repair(Membrane& m, const Snapshot& last_good, uint32_t i) {
  Particles& p = m.particles;
  bool repaired = false;
  if (!finite3(p.x[i], p.y[i], p.z[i])) {
    repaired = true;
    const uint32_t n = p.slots.size();
    if (last_good.x.size() == n && finite3(last_good.x[i], last_good.y[i], last_good.z[i])) {
      p.x[i] = last_good.x[i], p.y[i] = last_good.y[i], p.z[i] = last_good.z[i];
    } else if (m.glue && m.glue->x.size() == n &&
               finite3(m.glue->x[i], m.glue->y[i], m.glue->z[i])) {
      p.x[i] = m.glue->x[i], p.y[i] = m.glue->y[i], p.z[i] = m.glue->z[i];
    } else {
      p.x[i] = p.y[i] = p.z[i] = 0.0f;
    }
    p.vx[i] = p.vy[i] = p.vz[i] = 0.0f;
  }
  if (!finite3(p.vx[i], p.vy[i], p.vz[i])) {
    repaired = true;
    p.vx[i] = p.vy[i] = p.vz[i] = 0.0f;
  }
  return repaired;
}

}  // namespace

uint32_t sanitize_and_save(Membrane& m, Snapshot& snap) {
  Particles& p = m.particles;
  const uint32_t n = p.slots.size();
  uint32_t repaired = 0;
  if (snap.x.size() > n ||
      snap.x.empty()) {  // first use: repair against nothing, copy every particle
    for (uint32_t i = 0; i < n; ++i) repaired += repair(m, snap, i) ? 1 : 0;
    snap.x = p.x, snap.y = p.y, snap.z = p.z, snap.vx = p.vx, snap.vy = p.vy, snap.vz = p.vz;
    return repaired;
  }
  if (snap.x.size() < n) {
    // A cut or a tear added particles at the end of the table: save just those (amortised
    // growth), not the whole mesh again, so a cut frame costs what the cut touched (issue 17).
    const uint32_t old_n = static_cast<uint32_t>(snap.x.size());
    for (uint32_t i = old_n; i < n; ++i) repaired += repair(m, snap, i) ? 1 : 0;  // no snapshot yet
    for (auto* col : {&snap.x, &snap.y, &snap.z, &snap.vx, &snap.vy, &snap.vz}) col->resize(n);
    for (uint32_t i = old_n; i < n; ++i) {
      snap.x[i] = p.x[i], snap.y[i] = p.y[i], snap.z[i] = p.z[i];
      snap.vx[i] = p.vx[i], snap.vy[i] = p.vy[i], snap.vz[i] = p.vz[i];
    }
  }
  const ParticleSet set = particles_in_play(m);
  for (const uint32_t e : m.active_springs) {  // sleeping ends are read by the spring pass
    if (m.active.empty()) break;
    repaired += repair(m, snap, m.springs.i[e]) ? 1 : 0;
    repaired += repair(m, snap, m.springs.j[e]) ? 1 : 0;
  }
  // Each chunk repairs and saves its own particles; only the count is merged.
  repaired += parallel_reduce_ordered(
      0u, set.size(), kParticleGrain, uint32_t{0},
      [&](uint32_t begin, uint32_t end) {
        uint32_t count = 0;
        for (uint32_t k = begin; k < end; ++k) {
          const uint32_t i = set[k];
          count += repair(m, snap, i) ? 1 : 0;
          snap.x[i] = p.x[i], snap.y[i] = p.y[i], snap.z[i] = p.z[i];
          snap.vx[i] = p.vx[i], snap.vy[i] = p.vy[i], snap.vz[i] = p.vz[i];
        }
        return count;
      },
      [](uint32_t a, uint32_t b) { return a + b; });
  return repaired;
}

void hold_still(Membrane& m) {
  Particles& p = m.particles;
  const ParticleSet set = particles_in_play(m);
  parallel_for(0u, set.size(), kParticleGrain, [&](uint32_t begin, uint32_t end, int) {
    for (uint32_t k = begin; k < end; ++k) {
      const uint32_t i = set[k];
      if (p.kind[i] == ParticleKind::Free) p.vx[i] = p.vy[i] = p.vz[i] = 0.0f;
    }
  });
}

}  // namespace phaco::deform
