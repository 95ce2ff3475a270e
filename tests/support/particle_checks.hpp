#pragma once
// Test support: checks on a particle table's state.
#include <cmath>
#include <cstdint>
#include <span>

#include "components/particles.hpp"
#include "engine/core/state_hash.hpp"

namespace phaco::test {

// Every position and velocity finite.
inline bool all_finite(const Particles& p) {
  for (uint32_t i = 0; i < p.slots.size(); ++i)
    for (float v : {p.x[i], p.y[i], p.z[i], p.vx[i], p.vy[i], p.vz[i]})
      if (!std::isfinite(v)) return false;
  return true;
}

// Bit-exact hash of positions and velocities, for determinism checks.
inline uint64_t hash_state(const Particles& p) {
  StateHash h;
  for (const std::vector<float>* col : {&p.x, &p.y, &p.z, &p.vx, &p.vy, &p.vz})
    h.add(std::span<const float>(*col));
  return h.value();
}

}  // namespace phaco::test
