#pragma once
// The particles a deform step works on (the active node set, or every particle when it is
// empty), the effective mass that mass scaling gives them, and the health figures an integrator
// returns so the divergence guard needs no extra pass.
//
// Reads: Membrane::active, particles (inv_mass, kind), dynamics (mass_scale). Writes nothing.
#include <cmath>
#include <cstdint>
#include <span>

#include "engine/schedule/parallel.hpp"
#include "systems/deform/membrane.hpp"

namespace phaco::deform {

// Particles per parallel chunk in per-particle loops: large enough that a chunk's work dwarfs
// the task overhead, small enough that a level-3 capsule (8k) splits over two cores.
constexpr uint32_t kParticleGrain = 2048;

struct ParticleSet {
  std::span<const uint32_t> list;  // empty: every particle 0..count-1
  uint32_t count = 0;

  uint32_t operator[](uint32_t k) const { return list.empty() ? k : list[k]; }
  uint32_t size() const { return count; }
};

inline ParticleSet particles_in_play(const Membrane& m) {
  if (m.active.empty()) return {{}, m.particles.slots.size()};
  return {m.active, static_cast<uint32_t>(m.active.size())};
}

inline float inverse_mass_scale(const Dynamics& d) {
  return d.mass_scale > 0.0f ? 1.0f / d.mass_scale : 1.0f;
}

// 1/(m·mass_scale) for a particle that integrates (free, finite mass), else 0.
inline float integrating_inv_mass(const Particles& p, uint32_t i, float inv_scale) {
  return p.kind[i] == ParticleKind::Free ? p.inv_mass[i] * inv_scale : 0.0f;
}
inline float integrating_inv_mass(const Membrane& m, uint32_t i) {
  return integrating_inv_mass(m.particles, i, inverse_mass_scale(m.dynamics));
}

// What an integration pass saw on the particles it moved.
struct Motion {
  float max_speed_mm_s = 0.0f;
  uint32_t bad = 0;             // particles with a non-finite state or a speed above the bound
  uint32_t rejected_loads = 0;  // non-finite external loads ignored by the force pass
};

// A chunk's running figures; branch-free to update so the integration loops vectorise.
struct ChunkMotion {
  float max_speed2 = 0.0f;  // (mm/s)², over the particles that passed
  uint32_t bad = 0;
};

// Records one particle. `moved` false (a particle the pass does not integrate) records nothing.
// x − x is 0 for a finite x and NaN for ±inf or NaN, and NaN fails every comparison.
inline void observe(ChunkMotion& c, bool moved, float x, float y, float z, float vx, float vy,
                    float vz, float limit2) {
  const float s2 = vx * vx + vy * vy + vz * vz;
  const bool ok = (s2 <= limit2) & (x - x == 0.0f) & (y - y == 0.0f) & (z - z == 0.0f);
  c.bad += (moved & !ok) ? 1u : 0u;
  c.max_speed2 = (moved & ok & (s2 > c.max_speed2)) ? s2 : c.max_speed2;
}

inline float speed_limit2(const Membrane& m) {
  const float v = m.dynamics.max_speed_mm_s > 0.0f ? m.dynamics.max_speed_mm_s : 1.0e4f;
  return v * v;
}

// Runs fn(i, chunk) for every particle in play, in parallel chunks that do not depend on the
// thread count, and merges the chunks in order.
template <class Fn>
Motion for_each_in_play(const ParticleSet& set, Fn&& fn) {
  const ChunkMotion total = parallel_reduce_ordered(
      0u, set.size(), kParticleGrain, ChunkMotion{},
      [&](uint32_t begin, uint32_t end) {
        ChunkMotion local;
        if (set.list.empty()) {
          for (uint32_t i = begin; i < end; ++i) fn(i, local);
        } else {
          for (uint32_t k = begin; k < end; ++k) fn(set.list[k], local);
        }
        return local;
      },
      [](ChunkMotion a, const ChunkMotion& b) {
        a.max_speed2 = a.max_speed2 > b.max_speed2 ? a.max_speed2 : b.max_speed2;
        a.bad += b.bad;
        return a;
      });
  return {std::sqrt(total.max_speed2), total.bad, 0};
}

}  // namespace phaco::deform
