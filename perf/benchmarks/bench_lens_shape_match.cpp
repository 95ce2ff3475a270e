// Micro-benchmarks of shape matching (systems/shape_match): one fragment's solve by Horn (Eigen's
// dense solver or the characteristic quartic, float or double), by MHTG05 polar decomposition, and
// by the policy (match_fragment), for fragments of 1–64 cells; and one whole-lens pass (level 3,
// ≈ 53k cells) split into 1, 100, 5000 fragments on 1 and 2 threads.
//   build/release/perf/benchmarks/bench_lens_shape_match --benchmark_min_time=0.2
// Counters: ns per fragment (a batch of 256 different fragments per iteration), ns per cell.
#include <benchmark/benchmark.h>
#include <oneapi/tbb/task_arena.h>

#include <map>
#include <memory>
#include <span>
#include <vector>

#include "perf/lens/shape_match_fixture.hpp"
#include "systems/shape_match/shape_match.hpp"

namespace phaco::perf {
namespace {

using shape_match::Solver;

constexpr int kBatch = 256;

struct Batch {
  std::vector<std::vector<Vec3>> rest, cur;
  std::vector<std::vector<Vec3f>> rest_f, cur_f;
};

const Batch& batch(int cells) {
  static std::map<int, std::unique_ptr<Batch>> cache;
  auto& slot = cache[cells];
  if (!slot) {
    slot = std::make_unique<Batch>();
    shape::Gen g(static_cast<uint64_t>(cells));
    for (int k = 0; k < kBatch; ++k) {
      std::vector<Vec3> a = shape::box_cloud(g, cells), b(cells);
      const Quat r = g.rotation();
      for (int i = 0; i < cells; ++i) b[i] = r * a[i] + Vec3(0.1, 0.2, 0.3) + 0.01 * g.in_box(1);
      std::vector<Vec3f> af(cells), bf(cells);
      for (int i = 0; i < cells; ++i) af[i] = a[i].cast<float>(), bf[i] = b[i].cast<float>();
      slot->rest.push_back(a);
      slot->cur.push_back(b);
      slot->rest_f.push_back(af);
      slot->cur_f.push_back(bf);
    }
  }
  return *slot;
}

template <class T>
std::span<const T> cs(const std::vector<T>& v) {
  return {v.data(), v.size()};
}

template <class Fn>
void run_batch(benchmark::State& state, Fn&& one) {
  const Batch& b = batch(static_cast<int>(state.range(0)));
  for (auto _ : state)
    for (int k = 0; k < kBatch; ++k) benchmark::DoNotOptimize(one(b, k));
  state.counters["ns_per_fragment"] =
      benchmark::Counter(static_cast<double>(state.iterations()) * kBatch * 1e-9,
                         benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}

template <class T, Solver S>
void BM_Horn(benchmark::State& state) {
  run_batch(state, [](const Batch& b, int k) {
    if constexpr (sizeof(T) == 4)
      return shape_match::horn<float, float>(cs(b.rest_f[k]), cs(b.cur_f[k]), {}, S).rotation.w();
    else
      return shape_match::horn<double, double>(cs(b.rest[k]), cs(b.cur[k]), {}, S).rotation.w();
  });
}

template <class T>
void BM_Polar(benchmark::State& state) {
  run_batch(state, [](const Batch& b, int k) {
    if constexpr (sizeof(T) == 4)
      return shape_match::polar<float, float>(cs(b.rest_f[k]), cs(b.cur_f[k]), {}, true).det;
    else
      return shape_match::polar<double, double>(cs(b.rest[k]), cs(b.cur[k]), {}, true).det;
  });
}

void BM_Policy(benchmark::State& state) {
  run_batch(state, [](const Batch& b, int k) {
    return shape_match::match_fragment<double>(cs(b.rest[k]), cs(b.cur[k]), {}, Quat::Identity())
        .rotation.w();
  });
}

#define PHACO_SIZES ->Arg(1)->Arg(2)->Arg(3)->Arg(4)->Arg(8)->Arg(64)
BENCHMARK(BM_Horn<float, Solver::Eigen>) PHACO_SIZES;
BENCHMARK(BM_Horn<double, Solver::Eigen>) PHACO_SIZES;
BENCHMARK(BM_Horn<float, Solver::Quartic>) PHACO_SIZES;
BENCHMARK(BM_Horn<double, Solver::Quartic>) PHACO_SIZES;
BENCHMARK(BM_Polar<float>) PHACO_SIZES;
BENCHMARK(BM_Polar<double>) PHACO_SIZES;
BENCHMARK(BM_Policy) PHACO_SIZES;
#undef PHACO_SIZES

// The whole-lens pass: args (fragments, threads).
void BM_LensPass(benchmark::State& state) {
  static std::map<int64_t, std::unique_ptr<shape::LensFragments>> cache;
  auto& slot = cache[state.range(0)];
  if (!slot)
    slot = std::make_unique<shape::LensFragments>(
        shape::make_lens_fragments(3, static_cast<uint32_t>(state.range(0))));
  shape::LensFragments& l = *slot;
  shape_match::MatchSettings settings;
  settings.stiffness = 0.5;
  tbb::task_arena arena(static_cast<int>(state.range(1)));
  arena.execute([&] {
    for (auto _ : state)
      benchmark::DoNotOptimize(
          shape_match::match_lens<float>(cs(l.rest), {l.current.data(), l.current.size()},
                                         cs(l.mass), shape_match::FragmentList{l.offsets, l.cells},
                                         {l.rotations.data(), l.rotations.size()}, settings));
  });
  state.counters["cells"] = static_cast<double>(l.rest.size());
  state.counters["ns_per_cell"] = benchmark::Counter(
      static_cast<double>(state.iterations()) * static_cast<double>(l.rest.size()) * 1e-9,
      benchmark::Counter::kIsRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_LensPass)
    ->ArgsProduct({{1, 100, 5000}, {1, 2}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace
}  // namespace phaco::perf
