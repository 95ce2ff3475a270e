#pragma once
// Measurements of the SPH neighbour search (systems/sph) for the `phaco-perf lens` study: the
// grid build (keys + sort + cell table) and the neighbour pass (density: every candidate of the
// 2×2×2 block tested, ≈ 28 neighbours summed) per particle count, cell order and thread count.
// Returns rows only; the harness prints and charts them.
//
// The cloud: N points uniform in a cube, in random input order (the unsorted hash sees them in
// that order), at a density giving 28 neighbours per particle on average: ρ·(4/3)πh³ = 28 with
// h = 1 (the figures scale with h).
#include <cstdint>
#include <vector>

#include "systems/sph/grid.hpp"

namespace phaco::perf {

struct SphMeasureOptions {
  std::vector<uint32_t> sizes = {10'000, 100'000};  // add 1'000'000 for the large row
  std::vector<sph::CellOrder> orders = {sph::CellOrder::Morton, sph::CellOrder::Linear,
                                        sph::CellOrder::UnsortedHash};
  std::vector<int> threads = {1, 2};
  std::vector<bool> subcells = {true, false};  // sorted orders: sub-cell runs, 2×2×2 block runs
  double neighbours = 28.0;                    // target mean neighbours per particle
  double min_seconds = 0.2;                    // per timing repeat
  int repeats = 3;
  uint32_t seed = 1;
};

struct SphRow {
  uint32_t particles = 0;
  sph::CellOrder order = sph::CellOrder::Morton;
  int threads = 1;
  bool subcells = false;         // sorted orders: scanned the 27 sub-cells (else the 2×2×2 block)
  double build_ms = 0.0;         // build_grid: keys, sort, cell table (or hash table)
  double pass_ms = 0.0;          // density_pass
  double mean_neighbours = 0.0;  // measured
  double candidates = 0.0;       // mean candidates tested per particle (the hash: as the block)
  double ns_per_candidate = 0.0;  // pass time / (particles · candidates)
};

// The default options with the 1M row added when `with_million`.
SphMeasureOptions sph_default_options(bool with_million);

std::vector<SphRow> measure_sph(const SphMeasureOptions& options);

}  // namespace phaco::perf
