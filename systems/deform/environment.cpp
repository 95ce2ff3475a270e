#include "systems/deform/environment.hpp"

#include <cmath>

#include "systems/deform/particle_set.hpp"

namespace phaco::deform {

namespace {

struct Point {
  double x, y, z;
};

double half_axis(const Environment& env, double z) {
  return z >= 0.0 ? env.lens_anterior_mm : env.lens_posterior_mm;
}

// ∇q, up to the factor 2 that cancels in every use below.
Point lens_gradient(const Environment& env, const Point& p) {
  const double r2 = env.lens_radius_mm * env.lens_radius_mm, c = half_axis(env, p.z);
  return {p.x / r2, p.y / r2, p.z / (c * c)};
}

// Moves p onto the lens surface; returns the outward unit normal there.
Point project_on_lens(const Environment& env, Point& p) {
  double q = lens_level(env, p.x, p.y, p.z);
  if (q >= 0.25) {
    for (int it = 0; it < 3 && q < 1.0; ++it) {
      const Point g = lens_gradient(env, p);
      const double g2 = g.x * g.x + g.y * g.y + g.z * g.z;
      // q − 1 with ∇q = 2g: x ← x − (q − 1)·2g / (4|g|²)
      const double t = (1.0 - q) / (2.0 * g2);
      p = {p.x + t * g.x, p.y + t * g.y, p.z + t * g.z};
      q = lens_level(env, p.x, p.y, p.z);
    }
  }
  // The Newton steps may overshoot a little; scaling from the centre lands exactly on q = 1.
  if (q <= 0.0) {
    p = {0.0, 0.0, env.lens_anterior_mm};  // the centre itself: the anterior pole
  } else if (q != 1.0) {
    const double s = 1.0 / std::sqrt(q);
    p = {p.x * s, p.y * s, p.z * s};
  }
  const Point g = lens_gradient(env, p);
  const double gn = std::sqrt(g.x * g.x + g.y * g.y + g.z * g.z);
  return {g.x / gn, g.y / gn, g.z / gn};
}

}  // namespace

double lens_level(const Environment& env, double x, double y, double z) {
  const double r = env.lens_radius_mm, c = half_axis(env, z);
  return (x * x + y * y) / (r * r) + z * z / (c * c);
}

uint32_t apply_environment(Membrane& m) {
  if (!m.environment || (!m.environment->has_lens && !m.environment->has_cornea)) return 0;
  const Environment& env = *m.environment;
  Particles& p = m.particles;
  const ParticleSet set = particles_in_play(m);
  return parallel_reduce_ordered(
      0u, set.size(), kParticleGrain, uint32_t{0},
      [&](uint32_t begin, uint32_t end) {
        uint32_t corrected = 0;
        for (uint32_t k = begin; k < end; ++k) {
          const uint32_t i = set[k];
          if (p.kind[i] != ParticleKind::Free) continue;
          Point pos{p.x[i], p.y[i], p.z[i]};
          Point normal{0, 0, 0};
          double sign =
              0.0;  // +1: the obstacle is on the normal's negative side (lens), −1: positive side
          if (env.has_lens && lens_level(env, pos.x, pos.y, pos.z) < 1.0) {
            normal = project_on_lens(env, pos);
            sign = 1.0;
          } else if (env.has_cornea) {
            const double dx = pos.x, dy = pos.y, dz = pos.z - env.cornea_centre_z_mm;
            const double r = std::sqrt(dx * dx + dy * dy + dz * dz);
            if (r > env.cornea_radius_mm) {
              const double s = env.cornea_radius_mm / r;
              pos = {dx * s, dy * s, env.cornea_centre_z_mm + dz * s};
              normal = {dx / r, dy / r, dz / r};
              sign = -1.0;
            }
          }
          if (sign == 0.0) continue;
          ++corrected;
          p.x[i] = static_cast<float>(pos.x), p.y[i] = static_cast<float>(pos.y),
          p.z[i] = static_cast<float>(pos.z);
          const double vn = p.vx[i] * normal.x + p.vy[i] * normal.y + p.vz[i] * normal.z;
          if (sign * vn < 0.0) {  // moving into the obstacle
            p.vx[i] = static_cast<float>(p.vx[i] - vn * normal.x);
            p.vy[i] = static_cast<float>(p.vy[i] - vn * normal.y);
            p.vz[i] = static_cast<float>(p.vz[i] - vn * normal.z);
          }
        }
        return corrected;
      },
      [](uint32_t a, uint32_t b) { return a + b; });
}

}  // namespace phaco::deform
