// Micro-benchmarks of the simplex cells (systems/simplex) on the level-3 lens (≈ 53k cells): the
// removal primitive per simplex (crater order from the anterior pole, the structure restored
// outside the timed region every 2,000 removals), the dual boundary surface, and fragment
// labelling by painting and by the parallel union-find.
//   build/perf/bench_lens_simplex --benchmark_min_time=0.5s
#include <benchmark/benchmark.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <numeric>

#include "procedures/eye/eye_mesh.hpp"
#include "procedures/eye/eye_params.hpp"
#include "procedures/eye/resolution.hpp"
#include "systems/simplex/simplex_cells.hpp"
#include "systems/simplex/simplex_fragments.hpp"
#include "systems/simplex/simplex_surface.hpp"

namespace phaco::simplex {
namespace {

const SimplexCells& lens_cells() {
  static const SimplexCells cells =
      build_cells(eye::make_lens_tets(eye::default_eye_params(), eye::resolution_for_level(3)));
  return cells;
}

void BM_RemoveCellCrater(benchmark::State& state) {
  const SimplexCells& base = lens_cells();
  std::vector<uint32_t> order(base.size());
  std::iota(order.begin(), order.end(), 0u);
  auto d2 = [&](uint32_t c) {
    const float z = base.rest_z[c] - 1.8f;
    return base.rest_x[c] * base.rest_x[c] + base.rest_y[c] * base.rest_y[c] + z * z;
  };
  std::stable_sort(order.begin(), order.end(),
                   [&](uint32_t a, uint32_t b) { return d2(a) < d2(b); });
  SimplexCells cells = base;
  size_t next = 0;
  for (auto _ : state) {
    if (next == 2000) {
      state.PauseTiming();
      cells = base;
      next = 0;
      state.ResumeTiming();
    }
    benchmark::DoNotOptimize(remove_cell(cells, order[next++]));
  }
}
BENCHMARK(BM_RemoveCellCrater);

void BM_BoundarySurface(benchmark::State& state) {
  BoundarySurface surface;
  for (auto _ : state) {
    build_boundary_surface(lens_cells(), surface);
    benchmark::DoNotOptimize(surface.triangles.data());
  }
}
BENCHMARK(BM_BoundarySurface)->Unit(benchmark::kMillisecond);

void BM_LabelPainting(benchmark::State& state) {
  Fragments frags;
  FragmentScratch scratch;
  for (auto _ : state) label_fragments_painting(lens_cells(), frags, scratch);
}
BENCHMARK(BM_LabelPainting)->Unit(benchmark::kMillisecond);

void BM_LabelUnionFind(benchmark::State& state) {
  Fragments frags;
  FragmentScratch scratch;
  tbb::task_arena arena(static_cast<int>(state.range(0)));
  for (auto _ : state)
    arena.execute([&] { label_fragments_union_find(lens_cells(), frags, scratch); });
}
BENCHMARK(BM_LabelUnionFind)->Arg(1)->Arg(2)->Unit(benchmark::kMillisecond);

}  // namespace
}  // namespace phaco::simplex
