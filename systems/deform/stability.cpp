#include "systems/deform/stability.hpp"

#include <algorithm>
#include <cmath>

#include "systems/deform/deform.hpp"

namespace phaco::deform {

namespace {

// The test body: particles, springs with the probe's k and m, and its initial displacement.
struct ProbeBodyData {
  Particles particles;
  Springs springs;
  SpringBlocks blocks;
  Forces forces;
  Dynamics dynamics;
  std::vector<float> rest_x, rest_y, rest_z;  // before the initial displacement, mm
};

// The linear stability question stops making sense once a particle has travelled a good part of
// the spacing (a spring may then fold through its anchor and cap a growing mode); such a trial
// counts as unstable.
constexpr float kMaxDisplacement = 0.25f;  // of the (unit) spacing

bool left_linear_regime(const ProbeBodyData& b) {
  const Particles& p = b.particles;
  for (uint32_t i = 0; i < p.slots.size(); ++i) {
    const float dx = p.x[i] - b.rest_x[i], dy = p.y[i] - b.rest_y[i], dz = p.z[i] - b.rest_z[i];
    if (!(dx * dx + dy * dy + dz * dz <= kMaxDisplacement * kMaxDisplacement)) return true;
  }
  return false;
}

void add_particle(Particles& p, float x, float y, ParticleKind kind, float inv_mass) {
  const uint32_t i = table_add(p);
  p.x[i] = x, p.y[i] = y, p.z[i] = 0.0f;
  p.vx[i] = p.vy[i] = p.vz[i] = 0.0f;
  p.kind[i] = kind;
  p.inv_mass[i] = kind == ParticleKind::Free ? inv_mass : 0.0f;
}

void add_spring(Springs& s, const Particles& p, uint32_t a, uint32_t b, float k) {
  const uint32_t e = table_add(s);
  s.i[e] = std::min(a, b), s.j[e] = std::max(a, b);
  const float dx = p.x[b] - p.x[a], dy = p.y[b] - p.y[a];
  s.rest_length[e] = std::sqrt(dx * dx + dy * dy);
  s.stiffness[e] = k;
}

// Deterministic displacement in [−1, 1] from (particle, axis): a small integer hash.
float pattern(uint32_t i, uint32_t axis) {
  uint32_t h = i * 0x9E3779B1u ^ (axis + 1) * 0x85EBCA77u;
  h ^= h >> 15, h *= 0x2C1B3C6Du, h ^= h >> 12;
  return static_cast<float>(h % 2001u) / 1000.0f - 1.0f;
}

void build(ProbeBodyData& b, double k, double mass, const StabilityProbe& probe) {
  const float inv = static_cast<float>(1.0 / mass), kf = static_cast<float>(k);
  if (probe.body == ProbeBody::SpringMass) {
    add_particle(b.particles, 0.0f, 0.0f, ParticleKind::Anchored, 0.0f);
    add_particle(b.particles, 1.0f, 0.0f, ParticleKind::Free, inv);
    add_spring(b.springs, b.particles, 0, 1, kf);
  } else {
    const uint32_t n = std::max<uint32_t>(probe.patch_side, 3);
    for (uint32_t r = 0; r < n; ++r) {
      for (uint32_t c = 0; c < n; ++c) {
        const bool rim = r == 0 || c == 0 || r == n - 1 || c == n - 1;
        add_particle(b.particles, static_cast<float>(c), static_cast<float>(r),
                     rim ? ParticleKind::Anchored : ParticleKind::Free, inv);
      }
    }
    // Sorted by (i, j) as the block planner requires: right, up-left diagonal, up... per particle.
    for (uint32_t r = 0; r < n; ++r) {
      for (uint32_t c = 0; c < n; ++c) {
        const uint32_t v = r * n + c;
        if (c + 1 < n) add_spring(b.springs, b.particles, v, v + 1, kf);
        if (r + 1 < n && c > 0) add_spring(b.springs, b.particles, v, v + n - 1, kf);
        if (r + 1 < n) add_spring(b.springs, b.particles, v, v + n, kf);
      }
    }
  }
  b.blocks.particle_begin = {0, b.particles.slots.size()};
  b.blocks.spring_begin = {0, b.springs.slots.size()};
  b.rest_x = b.particles.x, b.rest_y = b.particles.y, b.rest_z = b.particles.z;
  const float amplitude = 1e-2f;  // of the (unit) spacing
  for (uint32_t i = 0; i < b.particles.slots.size(); ++i) {
    if (b.particles.kind[i] != ParticleKind::Free) continue;
    b.particles.x[i] += amplitude * pattern(i, 0);
    b.particles.y[i] += amplitude * pattern(i, 1);
    b.particles.z[i] += amplitude * pattern(i, 2);
  }
  b.dynamics.law = probe.law;
  b.dynamics.damping_per_s = static_cast<float>(probe.damping_per_s);
  b.dynamics.max_speed_mm_s = 3.0e38f;  // the trial judges by energy, not by a speed cap
  b.forces.resize_zero(b.particles.slots.size());
}

}  // namespace

bool is_stable(Integrator integrator, double k, double mass, double dt,
               const StabilityProbe& probe) {
  ProbeBodyData b;
  build(b, k, mass, probe);
  b.dynamics.integrator = integrator;
  Membrane m{b.particles, b.springs, b.blocks, b.forces, b.dynamics};
  DeformState st;
  st.xpbd.iterations = probe.xpbd_iterations;
  if (!(measure_energy(m).stored() > 0.0)) return true;
  const uint32_t half = std::max<uint32_t>(probe.steps / 2, 1);
  double first_max = 0.0, second_max = 0.0;
  for (uint32_t s = 0; s < std::max(probe.steps, 2 * half); ++s) {
    const Motion motion = integrate_once(m, dt, integrator, st);
    if (motion.bad > 0 || left_linear_regime(b)) return false;
    const double e = measure_energy(m).stored();
    if (!std::isfinite(e)) return false;
    (s < half ? first_max : second_max) = std::max(s < half ? first_max : second_max, e);
  }
  return second_max <= probe.growth_bound * first_max;
}

StabilityResult largest_stable_dt(Integrator integrator, double k, double mass,
                                  const StabilityProbe& probe) {
  StabilityResult r;
  r.omega_per_s = std::sqrt(k / mass);
  double lo = std::log(probe.min_omega_dt), hi = std::log(probe.max_omega_dt);
  const auto stable_at = [&](double log_omega_dt) {
    return is_stable(integrator, k, mass, std::exp(log_omega_dt) / r.omega_per_s, probe);
  };
  if (stable_at(hi)) {
    r.stable_everywhere = true;
    r.dt_max_s = probe.max_omega_dt / r.omega_per_s;
    return r;
  }
  if (!stable_at(lo)) {
    r.unstable_everywhere = true;
    return r;
  }
  for (int it = 0; it < probe.bisections; ++it) {
    const double mid = 0.5 * (lo + hi);
    (stable_at(mid) ? lo : hi) = mid;
  }
  r.dt_max_s = std::exp(lo) / r.omega_per_s;
  return r;
}

StabilityMap stability_map(Integrator integrator, std::span<const double> k_values,
                           std::span<const double> mass_values, const StabilityProbe& probe) {
  StabilityMap map;
  map.integrator = integrator;
  map.k_values.assign(k_values.begin(), k_values.end());
  map.mass_values.assign(mass_values.begin(), mass_values.end());
  for (const double k : k_values) {
    for (const double mass : mass_values)
      map.cells.push_back(largest_stable_dt(integrator, k, mass, probe));
  }
  return map;
}

}  // namespace phaco::deform
