#include "systems/sph/neighbours.hpp"

#include <algorithm>
#include <cassert>
#include <cstring>

#include "engine/core/invariants.hpp"
#include "engine/schedule/parallel.hpp"
#include "systems/sph/kernel.hpp"
#include "systems/sph/simd8.hpp"

namespace phaco::sph {

namespace {

using simd8::F8;
using simd8::I8;
using simd8::load8;
using simd8::splat;

constexpr uint32_t kNeighbourGrain = 1024;

// Σ m_j (h² − r²)³ over the candidates [b, e) inside h, eight at a time into lane sums and counts
// (candidate b + 8k + l goes to lane l, so a particle's sum does not depend on the chunking). The
// last block is masked by index: the columns are padded with kPad slots, so it may read past e.
inline void accumulate_run(const Grid& g, uint32_t b, uint32_t e, F8 xi, F8 yi, F8 zi, F8& acc,
                           I8& cnt) {
  const F8 h2 = splat(g.h2);
  const F8 zero = splat(0.0f);
  const float* X = g.x.data();
  const float* Y = g.y.data();
  const float* Z = g.z.data();
  const float* M = g.m.data();
  uint32_t j = b;
  for (; j + 8 <= e; j += 8) {
    const F8 dx = xi - load8(X + j), dy = yi - load8(Y + j), dz = zi - load8(Z + j);
    const F8 d = h2 - (dx * dx + dy * dy + dz * dz);
    const I8 in = d > zero;  // −1 where r² < h²
    const F8 w = in ? d : zero;
    acc += load8(M + j) * (w * w * w);
    cnt -= in;
  }
  if (j < e) {
    const I8 valid = simd8::below(j, e);
    const F8 dx = xi - load8(X + j), dy = yi - load8(Y + j), dz = zi - load8(Z + j);
    const F8 d = h2 - (dx * dx + dy * dy + dz * dz);
    const I8 in = (d > zero) & valid;
    const F8 w = in ? d : zero;
    acc += load8(M + j) * (w * w * w);
    cnt -= in;
  }
}

// The density pass over slots [b, e) of a sorted grid.
#if defined(__x86_64__) && defined(__GNUC__) && !defined(__clang__) && \
    !defined(__SANITIZE_ADDRESS__)
__attribute__((target_clones("avx2", "default")))
#endif
void density_chunk(const Grid& g, uint32_t b, uint32_t e, float norm, float* density,
                   uint32_t* neighbours) {
  Candidates candidates(g);
  for (uint32_t i = b; i < e; ++i) {
    F8 acc = splat(0.0f);
    I8 cnt = {};
    const F8 xi = splat(g.x[i]), yi = splat(g.y[i]), zi = splat(g.z[i]);
    for (const Run run : candidates.runs(i))
      accumulate_run(g, run.begin, run.end, xi, yi, zi, acc, cnt);
    float rho = 0.0f;
    uint32_t n = 0;
    for (int l = 0; l < 8; ++l) {
      rho += acc[l];
      n += static_cast<uint32_t>(cnt[l]);
    }
    density[g.id[i]] = norm * rho;
    neighbours[g.id[i]] = n - 1;  // the particle itself is in its own cell
  }
}

}  // namespace

void density_pass(const Grid& g, std::span<float> density, std::span<uint32_t> neighbours) {
  // Indexed like the spans the grid was built from: every slot's particle within them.
  assert(same_size(density, neighbours) && all_below(g.id, density.size()));
  const float norm = static_cast<float>(poly6_normalisation(g.h));
  if (g.order == CellOrder::UnsortedHash) {
    parallel_for(0, g.count, kNeighbourGrain, [&](uint32_t b, uint32_t e, int) {
      for (uint32_t i = b; i < e; ++i) {
        float rho = g.m[i] * g.h2 * g.h2 * g.h2;  // self: r = 0
        uint32_t n = 0;
        for_each_neighbour(g, i, i + 1, [&](uint32_t, uint32_t j, float, float, float, float r2) {
          const float d = g.h2 - r2;
          rho += g.m[j] * (d * d * d);
          ++n;
        });
        density[g.id[i]] = norm * rho;
        neighbours[g.id[i]] = n;
      }
    });
    return;
  }
  parallel_for(0, g.count, kNeighbourGrain, [&](uint32_t b, uint32_t e, int) {
    density_chunk(g, b, e, norm, density.data(), neighbours.data());
  });
}

void neighbour_lists(const Grid& g, uint32_t particle_count, std::vector<uint32_t>& offsets,
                     std::vector<uint32_t>& ids) {
  std::vector<std::vector<uint32_t>> lists(particle_count);
  for_each_neighbour(g, 0, g.count, [&](uint32_t i, uint32_t j, float, float, float, float) {
    lists[g.id[i]].push_back(g.id[j]);
  });
  offsets.assign(particle_count + 1, 0);
  ids.clear();
  for (uint32_t p = 0; p < particle_count; ++p) {
    std::sort(lists[p].begin(), lists[p].end());
    ids.insert(ids.end(), lists[p].begin(), lists[p].end());
    offsets[p + 1] = static_cast<uint32_t>(ids.size());
  }
}

}  // namespace phaco::sph
