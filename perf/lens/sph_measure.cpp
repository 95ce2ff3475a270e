#include "perf/lens/sph_measure.hpp"

#include <cmath>
#include <numbers>
#include <numeric>

#include "engine/core/rng.hpp"
#include "perf/timing.hpp"
#include "systems/sph/neighbours.hpp"

namespace phaco::perf {

namespace {

struct Cloud {
  std::vector<float> x, y, z, m;
};

// A cube of side L loses on average 1.125·h/L of the neighbours at its six faces (per face the
// ball's missing fraction averaged over the depth is 3/16 of h/L); the density is raised to
// make up for it, so the mean count is the target.
Cloud uniform_cloud(uint32_t n, double neighbours, uint32_t seed) {
  const double ball = 4.0 / 3.0 * std::numbers::pi;  // h = 1
  double side = std::cbrt(n * ball / neighbours);
  for (int k = 0; k < 20; ++k) side = std::cbrt(n * ball * (1.0 - 1.125 / side) / neighbours);
  CounterRng rng(seed, 0x5be4);
  Cloud c;
  c.x.resize(n), c.y.resize(n), c.z.resize(n), c.m.assign(n, 1.0f);
  for (uint32_t i = 0; i < n; ++i) {
    c.x[i] = static_cast<float>(side * rng.uniform_double(0, i, 0));
    c.y[i] = static_cast<float>(side * rng.uniform_double(0, i, 1));
    c.z[i] = static_cast<float>(side * rng.uniform_double(0, i, 2));
  }
  return c;
}

// Mean candidates per particle: the particles in each one's 2×2×2 block (sorted orders: the sum
// of its runs; the hash scans the same cells).
double mean_candidates(const sph::Grid& g) {
  if (g.order == sph::CellOrder::UnsortedHash || g.count == 0) return 0.0;
  sph::Candidates candidates(g);
  uint64_t total = 0;
  for (uint32_t i = 0; i < g.count; ++i)
    for (const sph::Run run : candidates.runs(i)) total += run.end - run.begin;
  return static_cast<double>(total) / g.count;
}

}  // namespace

SphMeasureOptions sph_default_options(bool with_million) {
  SphMeasureOptions o;
  if (with_million) o.sizes.push_back(1'000'000);
  return o;
}

std::vector<SphRow> measure_sph(const SphMeasureOptions& o) {
  std::vector<SphRow> rows;
  const float h = 1.0f;
  for (uint32_t n : o.sizes) {
    const Cloud c = uniform_cloud(n, o.neighbours, o.seed);
    double block_candidates = 0.0;  // what the hash scans: the 2×2×2 block of cells
    for (sph::CellOrder order : o.orders)
      for (bool subcells : o.subcells) {
        if (order == sph::CellOrder::UnsortedHash && subcells) continue;  // not applicable
        sph::Grid grid;
        grid.subcells = subcells;
        std::vector<float> rho(n);
        std::vector<uint32_t> count(n);
        for (int threads : o.threads) {
          SphRow row;
          row.particles = n;
          row.order = order;
          row.threads = threads;
          row.subcells = subcells && order != sph::CellOrder::UnsortedHash;
          row.build_ms = 1e3 * seconds_per_call(threads, o.min_seconds, o.repeats, [&] {
                           sph::build_grid(grid, c.x, c.y, c.z, c.m, h, order);
                         });
          row.pass_ms = 1e3 * seconds_per_call(threads, o.min_seconds, o.repeats,
                                               [&] { sph::density_pass(grid, rho, count); });
          row.mean_neighbours =
              static_cast<double>(std::accumulate(count.begin(), count.end(), uint64_t{0})) / n;
          if (order == sph::CellOrder::UnsortedHash) {
            row.candidates = block_candidates;
          } else {
            row.candidates = mean_candidates(grid);
            if (!subcells) block_candidates = row.candidates;
          }
          if (row.candidates > 0.0) row.ns_per_candidate = 1e6 * row.pass_ms / (n * row.candidates);
          rows.push_back(row);
        }
      }
  }
  return rows;
}

}  // namespace phaco::perf
