// Micro-benchmark of the SPH neighbour pass (systems/sph density_pass) per cell order at 10k and
// 100k particles, ≈ 28 neighbours each, uniform cloud in random input order; one thread (the
// issue's target: ≤ 10 ms at 100k on one core). The grid is built once outside the timed loop.
//   build-sph/perf/bench_lens_sph --benchmark_min_time=0.5
#include <benchmark/benchmark.h>
#include <oneapi/tbb/global_control.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "engine/core/rng.hpp"
#include "systems/sph/neighbours.hpp"

namespace phaco::sph {
namespace {

struct Fixture {
  std::vector<float> x, y, z, m, rho;
  std::vector<uint32_t> count;
  Grid grid;
};

Fixture make(uint32_t n, CellOrder order) {
  const double side = std::cbrt(n / (28.0 / (4.0 / 3.0 * std::numbers::pi)));
  CounterRng rng(1, 0x5be4);
  Fixture f;
  for (uint32_t i = 0; i < n; ++i) {
    f.x.push_back(static_cast<float>(side * rng.uniform_double(0, i, 0)));
    f.y.push_back(static_cast<float>(side * rng.uniform_double(0, i, 1)));
    f.z.push_back(static_cast<float>(side * rng.uniform_double(0, i, 2)));
  }
  f.m.assign(n, 1.0f);
  f.rho.resize(n);
  f.count.resize(n);
  build_grid(f.grid, f.x, f.y, f.z, f.m, 1.0f, order);
  return f;
}

void neighbour_pass(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const auto n = static_cast<uint32_t>(state.range(0));
  const auto order = static_cast<CellOrder>(state.range(1));
  Fixture f = make(n, order);
  for (auto _ : state) {
    density_pass(f.grid, f.rho, f.count);
    benchmark::DoNotOptimize(f.rho.data());
  }
  state.SetLabel(to_string(order));
  state.counters["ns_per_particle"] =
      benchmark::Counter(static_cast<double>(n), benchmark::Counter::kIsIterationInvariantRate |
                                                     benchmark::Counter::kInvert);
}

void grid_build(benchmark::State& state) {
  tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
  const auto n = static_cast<uint32_t>(state.range(0));
  const auto order = static_cast<CellOrder>(state.range(1));
  Fixture f = make(n, order);
  for (auto _ : state) {
    build_grid(f.grid, f.x, f.y, f.z, f.m, 1.0f, order);
    benchmark::DoNotOptimize(f.grid.id.data());
  }
  state.SetLabel(to_string(order));
}

void orders(benchmark::internal::Benchmark* b) {
  for (int64_t n : {10'000, 100'000})
    for (int64_t order : {0, 1, 2}) b->Args({n, order});
  b->Unit(benchmark::kMillisecond);
}

BENCHMARK(neighbour_pass)->Apply(orders);
BENCHMARK(grid_build)->Apply(orders);

}  // namespace
}  // namespace phaco::sph
