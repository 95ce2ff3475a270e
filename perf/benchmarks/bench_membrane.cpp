// Micro-benchmarks of the membrane's hot kernels on the pinned capsule (perf/membrane_fixture):
// the spring pass, the node pass and the plain SoA step, at 8k (level 3) and 128k (level 7)
// vertices, 1 and 2 threads. Counters: ns per vertex per step and bytes moved per second.
//   build/release/perf/bench_membrane --benchmark_min_time=0.2
#include <benchmark/benchmark.h>
#include <oneapi/tbb/task_arena.h>

#include <map>
#include <memory>

#include "perf/membrane_fixture.hpp"
#include "systems/springs/springs.hpp"

namespace phaco::perf {
namespace {

// Built once per level and reused by every benchmark of that level.
MembraneFixture& fixture(int level) {
  static std::map<int, std::unique_ptr<MembraneFixture>> cache;
  auto& slot = cache[level];
  if (!slot) {
    FixtureOptions o;
    o.level = level;
    slot = std::make_unique<MembraneFixture>(make_membrane_fixture(o));
  }
  return *slot;
}

template <class Fn>
void run(benchmark::State& state, double bytes_per_call, Fn&& fn) {
  MembraneFixture& m = fixture(static_cast<int>(state.range(0)));
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  arena.execute([&] {
    for (auto _ : state) fn(m);
  });
  const double n = static_cast<double>(state.iterations());
  state.counters["vertices"] = m.vertex_count();
  state.counters["ns_per_vertex"] = benchmark::Counter(
      n * m.vertex_count() * 1e-9, benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
  state.counters["bytes_per_s"] =
      benchmark::Counter(n * bytes_per_call, benchmark::Counter::kIsRate);
}

void BM_SpringPass(benchmark::State& state) {
  MembraneFixture& f = fixture(static_cast<int>(state.range(0)));
  run(state, spring_pass_bytes(f.vertex_count(), f.spring_count()), [](MembraneFixture& m) {
    springs::add_spring_forces(m.springs, m.blocks, m.options.law, m.particles, m.forces);
  });
  f.forces.resize_zero(f.vertex_count());
}

void BM_NodePass(benchmark::State& state) {
  MembraneFixture& f = fixture(static_cast<int>(state.range(0)));
  const float dt = static_cast<float>(f.stable_dt());
  run(state,
      plain_step_bytes(f.vertex_count(), f.spring_count()) -
          spring_pass_bytes(f.vertex_count(), f.spring_count()),
      [dt](MembraneFixture& m) { integrate_nodes(m.particles, m.forces, dt, 1000.0f); });
}

void BM_PlainStep(benchmark::State& state) {
  MembraneFixture& f = fixture(static_cast<int>(state.range(0)));
  const float dt = static_cast<float>(f.stable_dt());
  run(state, plain_step_bytes(f.vertex_count(), f.spring_count()),
      [dt](MembraneFixture& m) { plain_step(m, dt, 1000.0f, m.centre, -0.01f); });
}

BENCHMARK(BM_SpringPass)
    ->ArgsProduct({{3, 7}, {1, 2}})
    ->ArgNames({"level", "threads"})
    ->UseRealTime();
BENCHMARK(BM_NodePass)
    ->ArgsProduct({{3, 7}, {1, 2}})
    ->ArgNames({"level", "threads"})
    ->UseRealTime();
BENCHMARK(BM_PlainStep)
    ->ArgsProduct({{3, 7}, {1, 2}})
    ->ArgNames({"level", "threads"})
    ->UseRealTime();

}  // namespace
}  // namespace phaco::perf
