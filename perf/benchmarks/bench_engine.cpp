// Micro-benchmarks of the engine's own overheads: what every frame pays before any physics.
//   build/release/perf/bench_engine --benchmark_min_time=0.2
#include <benchmark/benchmark.h>
#include <oneapi/tbb/task_arena.h>
#include <pthread.h>
#include <sched.h>
#include <time.h>

#include <atomic>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "engine/core/rng.hpp"
#include "engine/core/state_hash.hpp"
#include "engine/core/table.hpp"
#include "engine/schedule/executor.hpp"
#include "engine/schedule/frame_graph.hpp"
#include "engine/schedule/parallel.hpp"
#include "engine/schedule/phased_team.hpp"
#include "perf/cores.hpp"

namespace phaco {
namespace {

// A frame of `n` empty systems in chains of four writers of one component each: the scheduler's
// cost per frame as a function of the number of systems, at 1 and 2 threads.
void BM_ExecutorFrame(benchmark::State& state) {
  const int n = static_cast<int>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  std::vector<SystemDesc> systems;
  for (int i = 0; i < n; ++i) {
    systems.push_back({.name = "s" + std::to_string(i),
                       .phase = Phase::Dynamics,
                       .writes = {"c" + std::to_string(i / 4)},
                       .run = [](const FrameContext&) {}});
  }
  FrameGraph graph(std::move(systems));
  Executor executor(graph, threads, AccessCheck::Off);
  constexpr uint64_t kKeptFrames = 1 << 14;  // timing samples kept; cleared, not regrown
  executor.reserve_frames(kKeptFrames);
  uint64_t frame = 0;
  for (auto _ : state) {
    executor.run_frame({frame++, 0.0, 1.0 / 120});
    if (frame % kKeptFrames == 0) executor.clear_timings();
  }
  state.counters["systems"] = n;
}
BENCHMARK(BM_ExecutorFrame)->ArgsProduct({{2, 8, 32, 128}, {1, 2}})->Unit(benchmark::kMicrosecond);

// One round trip of a cache line between two cores: the floor under every handoff of a team of
// two threads (PhasedTeam's phase opening, a chunk claim). Session 40's 2-vCPU VM, as the host
// moved its two vCPUs within minutes: 440–480 ns (apart), 112–117 ns (near), 70–80 ns (two
// hardware threads of one core: two compute loops then ran 1.3× slower side by side than alone).
// BM_PhasedTeamPhases on 2 threads ran 1.4–1.8× as fast as on 1 in the first two and 0.67× in
// the third (systems/deform/team_choice.hpp).
void BM_CoreRoundTrip(benchmark::State& state) {
  const auto [first, last] = perf::two_cpus();
  if (first < 0) {
    state.SkipWithError("needs two CPUs");
    return;
  }
  const perf::PinnedScope pin(first);
  perf::RoundTripPartner partner(last);
  for (auto _ : state) partner.trip();
}
BENCHMARK(BM_CoreRoundTrip)->Unit(benchmark::kNanosecond)->UseRealTime();

// A 1 kHz thread beside the benchmark, as the haptic loop is beside the frames: it sleeps to each
// deadline (SCHED_FIFO if granted) and then works `busy_us`, so it takes a core ~1000 times a
// second.
class KiloHertzNeighbour {
 public:
  explicit KiloHertzNeighbour(int busy_us) {
    thread_ = std::thread([this, busy_us] {
      sched_param param{};
      param.sched_priority = 80;
      pthread_setschedparam(pthread_self(), SCHED_FIFO, &param);
      timespec t;
      clock_gettime(CLOCK_MONOTONIC, &t);
      int64_t next = int64_t(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
      while (!stop_.load(std::memory_order_relaxed)) {
        next += 1'000'000;
        const timespec wake{time_t(next / 1'000'000'000), long(next % 1'000'000'000)};
        clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &wake, nullptr);
        for (int64_t now = next; now < next + busy_us * 1000;) {
          clock_gettime(CLOCK_MONOTONIC, &t);
          now = int64_t(t.tv_sec) * 1'000'000'000 + t.tv_nsec;
        }
      }
    });
  }
  ~KiloHertzNeighbour() {
    stop_.store(true, std::memory_order_relaxed);
    thread_.join();
  }

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

// A PhasedTeam's phases at about the size of a CG iteration's phases on the capsule's active
// set (issue 17): 150 phases of 12 chunks over 6,000 doubles, each chunk a few µs, the team formed
// once per run as in implicit_euler_step. Arguments: threads (1, 2) and the neighbour's busy time
// per tick in µs (-1: no neighbour). Session 40's VM, three runs with the vCPUs on two cores:
// 2 threads 1.4–1.8× as fast as 1 with no neighbour, with a neighbour busy 0 µs a tick and with
// one busy 150 µs; so the team itself survives a 1 kHz thread beside it (on one core's two
// hardware threads it lost: BM_CoreRoundTrip above).
void BM_PhasedTeamPhases(benchmark::State& state) {
  const int threads = static_cast<int>(state.range(0));
  const int busy_us = static_cast<int>(state.range(1));
  constexpr uint32_t kRows = 6000, kChunks = 12, kPhases = 150;
  std::vector<double> x(kRows, 1.0), y(kRows, 2.0);
  std::optional<KiloHertzNeighbour> neighbour;
  if (busy_us >= 0) neighbour.emplace(busy_us);
  tbb::task_arena arena(threads);
  arena.execute([&] {
    for (auto _ : state) {
      PhasedTeam team(threads > 1);
      team.run(
          kChunks, kPhases, [](uint64_t) { return true; },
          [&](uint64_t phase, uint32_t chunk) {
            const uint32_t per = kRows / kChunks, begin = chunk * per, end = begin + per;
            for (int pass = 0; pass < 4; ++pass)
              for (uint32_t i = begin; i < end; ++i)
                x[i] = x[i] * 0.999 + y[i] * 1e-3 * double(phase & 1);
          });
      benchmark::DoNotOptimize(x.data());
    }
  });
  state.counters["phases"] = kPhases;
}
BENCHMARK(BM_PhasedTeamPhases)
    ->ArgsProduct({{1, 2}, {-1, 0, 150}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// parallel_for dispatch over 128k elements doing one fused multiply-add each.
void BM_ParallelForStream(benchmark::State& state) {
  const uint32_t n = 1u << 17;
  std::vector<float> x(n, 1.0f), v(n, 0.5f);
  const uint32_t grain = static_cast<uint32_t>(state.range(0));
  for (auto _ : state) {
    parallel_for(0, n, grain, [&](uint32_t b, uint32_t e, int) {
      for (uint32_t i = b; i < e; ++i) x[i] += v[i] * 0.008f;
    });
    benchmark::DoNotOptimize(x.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
}
BENCHMARK(BM_ParallelForStream)->Arg(1024)->Arg(4096)->Arg(16384);

// Where a second thread starts to pay (issue 17: "loops below a measured grain run serially"):
// n elements of about the work of one row of the capsule's implicit operator (a 3×3 block times
// seven neighbours), split in two chunks on 2 threads, against one chunk on 1 thread. The size at
// which the 2-thread time falls below the 1-thread time is the grain below which a loop should
// stay serial (engine/schedule/parallel.hpp runs a range within its grain without a task).
void BM_ParallelForGrain(benchmark::State& state) {
  const uint32_t n = static_cast<uint32_t>(state.range(0));
  const int threads = static_cast<int>(state.range(1));
  std::vector<double> x(3 * size_t(n) + 64, 1.0), y(3 * size_t(n), 0.0);
  tbb::task_arena arena(threads);
  const uint32_t grain = threads == 1 ? n : (n + 1) / 2;
  for (auto _ : state) {
    arena.execute([&] {
      parallel_for(0, n, grain, [&](uint32_t b, uint32_t e, int) {
        for (uint32_t r = b; r < e; ++r) {
          double acc[3] = {0.0, 0.0, 0.0};
          for (uint32_t k = 0; k < 7; ++k) {
            const double* xs = &x[3 * r + 3 * k];
            for (int a = 0; a < 3; ++a) acc[a] += 0.5 * xs[0] + 0.25 * xs[1] + 0.125 * xs[2] + a;
          }
          y[3 * r] = acc[0], y[3 * r + 1] = acc[1], y[3 * r + 2] = acc[2];
        }
      });
    });
    benchmark::DoNotOptimize(y.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()) * n);
}
BENCHMARK(BM_ParallelForGrain)
    ->ArgsProduct({{64, 256, 1024, 4096, 16384}, {1, 2}})
    ->Unit(benchmark::kMicrosecond);

void BM_Philox(benchmark::State& state) {
  const CounterRng rng(7);
  uint32_t i = 0;
  float acc = 0;
  for (auto _ : state) acc += rng.uniform(3, i++);
  benchmark::DoNotOptimize(acc);
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations()));
}
BENCHMARK(BM_Philox);

void BM_StateHash(benchmark::State& state) {
  const std::vector<float> column(static_cast<size_t>(state.range(0)), 1.25f);
  for (auto _ : state) {
    StateHash h;
    h.add(std::span<const float>(column));
    benchmark::DoNotOptimize(h.value());
  }
  state.SetBytesProcessed(static_cast<int64_t>(state.iterations()) * state.range(0) * 4);
}
BENCHMARK(BM_StateHash)->Arg(8192)->Arg(131072);

struct Column3 {
  SlotIndex slots;
  std::vector<float> x, y, z;
  template <class F>
  void for_each_column(F&& f) {
    f(x), f(y), f(z);
  }
};

// Compaction of a 128k-element table with one element in 16 removed (a sync point after heavy
// sculpting).
void BM_TableCompact(benchmark::State& state) {
  for (auto _ : state) {
    state.PauseTiming();
    Column3 t;
    table_append(t, 1u << 17);
    for (uint32_t i = 0; i < (1u << 17); i += 16) table_remove(t, i);
    state.ResumeTiming();
    benchmark::DoNotOptimize(table_compact(t).new_size);
  }
}
BENCHMARK(BM_TableCompact)->Unit(benchmark::kMicrosecond);

}  // namespace
}  // namespace phaco
