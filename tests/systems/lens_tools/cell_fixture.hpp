#pragma once
// Test cells: n cells uniform in a box, from a counter-based RNG (same cells on every run).
#include <oneapi/tbb/task_arena.h>

#include <cstdint>

#include "components/lens_cells.hpp"
#include "engine/core/math.hpp"
#include "engine/core/rng.hpp"

namespace phaco::lens_tools::test {

inline LensCells box_cells(uint32_t n, const Vec3& lo, const Vec3& hi, uint64_t seed = 11,
                           float mass_kg = 5e-9f, float hardness = 0.0f) {
  LensCells c;
  c.resize(n);
  const CounterRng rng(seed, 1);
  for (uint32_t i = 0; i < n; ++i) {
    c.x[i] = static_cast<float>(lo.x() + (hi.x() - lo.x()) * rng.uniform_double(0, i, 0));
    c.y[i] = static_cast<float>(lo.y() + (hi.y() - lo.y()) * rng.uniform_double(0, i, 1));
    c.z[i] = static_cast<float>(lo.z() + (hi.z() - lo.z()) * rng.uniform_double(0, i, 2));
    c.mass[i] = mass_kg;
    c.hardness[i] = hardness;
  }
  return c;
}

// Runs fn() inside an arena of `threads` threads.
template <class Fn>
void with_threads(int threads, Fn&& fn) {
  tbb::task_arena arena(threads);
  arena.execute(fn);
}

}  // namespace phaco::lens_tools::test
