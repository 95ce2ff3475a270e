#include "systems/sph/environment.hpp"

#include <cassert>
#include <cmath>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"

namespace phaco::sph {

uint32_t constrain_to_spheres(std::span<const ConstraintSphere> spheres,
                              const EnvironmentParticles& p, std::span<uint8_t> heavy) {
  assert(same_size(p.x, p.y, p.z, p.vx, p.vy, p.vz, heavy));
  const auto n = static_cast<uint32_t>(p.x.size());
  return parallel_reduce_ordered(
      0u, n, 2048, 0u,
      [&](uint32_t b, uint32_t e) {
        uint32_t count = 0;
        for (uint32_t i = b; i < e; ++i) {
          uint8_t hit = 0;
          for (const ConstraintSphere& s : spheres) {
            const float dx = p.x[i] - s.cx, dy = p.y[i] - s.cy, dz = p.z[i] - s.cz;
            const float r2 = dx * dx + dy * dy + dz * dz;
            const float R2 = s.radius * s.radius;
            if (s.keep_inside ? !(r2 > R2) : !(r2 < R2)) continue;  // allowed side (or NaN)
            float nx = 0.0f, ny = 0.0f, nz = 1.0f;  // a cell at the centre leaves along +z
            if (r2 > 0.0f) {
              const float inv = 1.0f / std::sqrt(r2);
              nx = dx * inv;
              ny = dy * inv;
              nz = dz * inv;
            }
            p.x[i] = s.cx + nx * s.radius;
            p.y[i] = s.cy + ny * s.radius;
            p.z[i] = s.cz + nz * s.radius;
            // Outward speed for keep_inside, inward for keep_outside: the part that broke the
            // constraint, removed.
            const float vn = p.vx[i] * nx + p.vy[i] * ny + p.vz[i] * nz;
            if (s.keep_inside ? vn > 0.0f : vn < 0.0f) {
              p.vx[i] -= vn * nx;
              p.vy[i] -= vn * ny;
              p.vz[i] -= vn * nz;
            }
            hit = 1;
          }
          heavy[i] = hit;
          count += hit;
        }
        return count;
      },
      [](uint32_t a, uint32_t b) { return a + b; });
}

}  // namespace phaco::sph
