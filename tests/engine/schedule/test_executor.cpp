#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <memory>
#include <stdexcept>
#include <thread>

#include "engine/schedule/executor.hpp"
#include "engine/schedule/parallel.hpp"
#include "tests/engine/schedule/alloc_counter.hpp"
#include "tests/engine/schedule/make_system.hpp"
#include "tests/engine/schedule/random_systems.hpp"
#include "tests/support/environment.hpp"

namespace phaco {
namespace {

using test::make_system;

// Per-system record of the last frame: tickets from one global counter bracket each run.
struct RunLog {
  std::atomic<uint64_t> ticket{0};
  std::unique_ptr<std::atomic<uint64_t>[]> start, end, runs, frame_seen;

  explicit RunLog(size_t n)
      : start(new std::atomic<uint64_t>[n]),
        end(new std::atomic<uint64_t>[n]),
        runs(new std::atomic<uint64_t>[n]),
        frame_seen(new std::atomic<uint64_t>[n]) {
    for (size_t i = 0; i < n; ++i) start[i] = end[i] = runs[i] = frame_seen[i] = 0;
  }
};

TEST(Executor, RunsEverySystemOnceAfterAllItsPredecessors) {
  for (const Dispatch dispatch : {Dispatch::Graph, Dispatch::Serial, Dispatch::Auto})
    for (int threads : {1, 2, 4}) {
      for (uint64_t seed : {11u, 12u}) {
        auto systems = test::random_systems(30, 8, seed);
        RunLog log(systems.size());
        // Registration index -> log slot; the graph reorders, so the run closure keeps its slot.
        for (size_t k = 0; k < systems.size(); ++k) {
          systems[k].run = [&log, k](const FrameContext& ctx) {
            log.start[k] = ++log.ticket;
            log.frame_seen[k] = ctx.frame;
            std::this_thread::yield();  // widen the window in which a wrong order would show
            ++log.runs[k];
            log.end[k] = ++log.ticket;
          };
        }
        const FrameGraph graph(systems);
        std::vector<size_t> slot(graph.size());  // graph index -> registration index
        for (size_t i = 0; i < graph.size(); ++i)
          slot[i] = std::stoul(graph.system(i).name.substr(1));

        Executor ex(graph, threads, {.access_check = AccessCheck::On, .dispatch = dispatch});
        ASSERT_TRUE(ex.checks_access());
        EXPECT_EQ(ex.threads(), threads);
        constexpr uint64_t kFrames = 15;
        for (uint64_t f = 0; f < kFrames; ++f) {
          ex.run_frame({f, f * 0.01, 0.01});
          for (size_t i = 0; i < graph.size(); ++i) {
            ASSERT_EQ(log.runs[slot[i]], f + 1) << graph.system(i).name;
            ASSERT_EQ(log.frame_seen[slot[i]], f);
            for (size_t j = 0; j < graph.size(); ++j) {
              if (graph.reaches(i, j)) {
                ASSERT_GT(log.start[slot[j]], log.end[slot[i]])
                    << graph.system(j).name << " started before " << graph.system(i).name
                    << " ended; threads " << threads << " seed " << seed << " dispatch "
                    << int(dispatch);
              }
            }
          }
        }
      }
    }
}

TEST(Executor, IndependentSystemsRunConcurrently) {
  PHACO_REQUIRE_ENVIRONMENT(std::thread::hardware_concurrency() >= 2, "needs 2 hardware threads");
  std::atomic<int> arrived{0};
  std::atomic<int> saw_other{0};
  // Each waits (bounded) for the other to start: both can only see it if they overlap in time.
  auto meet = [&](const FrameContext&) {
    arrived.fetch_add(1);
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
    while (arrived.load() < 2 && std::chrono::steady_clock::now() < deadline) {
      std::this_thread::yield();
    }
    if (arrived.load() >= 2) saw_other.fetch_add(1);
  };
  const FrameGraph graph({make_system("left_hand", {"tools.pose"}, {"left.grip"}, meet),
                          make_system("right_hand", {"tools.pose"}, {"right.grip"}, meet)});
  ASSERT_FALSE(graph.ordered(0, 1));
  Executor ex(graph, 2, AccessCheck::On);
  ex.run_frame({});
  EXPECT_EQ(arrived.load(), 2);
  EXPECT_EQ(saw_other.load(), 2) << "the two independent systems never overlapped";
}

// Auto hands a frame to the flow graph only while overlapping its branches is predicted to save
// more than the dispatch costs. The costs are measured, so each case sits far from its line: the
// small graph's line is raised to a second (no preemption of a 10 us system measures that), and
// the wide graph's 3 ms branches always measure at least 3 ms against the default 0.05 ms. Whether
// the default line pays is the harness's figure (perf/RESULTS.md, "Frame dispatch").
void busy_for(std::chrono::microseconds d) {
  const auto until = std::chrono::steady_clock::now() + d;
  while (std::chrono::steady_clock::now() < until) {
  }
}

TEST(Executor, AutoDispatchRunsSmallFramesSeriallyAndWideOnesThroughTheGraph) {
  using std::chrono::microseconds;
  auto tiny = [](const FrameContext&) { busy_for(microseconds(10)); };
  const FrameGraph small({make_system("a", {}, {"x"}, tiny), make_system("b", {}, {"y"}, tiny),
                          make_system("c", {"x", "y"}, {"z"}, tiny)});
  Executor ex_small(small, 2, {.dispatch_cost_ms = 1000.0});
  for (int f = 0; f < 10; ++f) ex_small.run_frame({});
  EXPECT_EQ(ex_small.graph_frames(), 1u) << "only the first frame, while costs are unknown";
  EXPECT_EQ(ex_small.serial_frames(), 9u);

  auto wide = [](const FrameContext&) { busy_for(microseconds(3000)); };
  const FrameGraph both(
      {make_system("left", {}, {"l"}, wide), make_system("right", {}, {"r"}, wide)});
  Executor ex_wide(both, 2);
  for (int f = 0; f < 5; ++f) ex_wide.run_frame({});
  EXPECT_EQ(ex_wide.graph_frames(), 5u);
  EXPECT_EQ(ex_wide.serial_frames(), 0u);

  // One thread has nobody to overlap with; Graph and Serial are taken as asked.
  Executor ex_one(both, 1);
  ex_one.run_frame({}), ex_one.run_frame({});
  EXPECT_EQ(ex_one.serial_frames(), 2u);
  Executor ex_graph(small, 2, {.dispatch = Dispatch::Graph});
  Executor ex_serial(both, 2, {.dispatch = Dispatch::Serial});
  for (int f = 0; f < 3; ++f) ex_graph.run_frame({}), ex_serial.run_frame({});
  EXPECT_EQ(ex_graph.graph_frames(), 3u);
  EXPECT_EQ(ex_serial.serial_frames(), 3u);
  EXPECT_THROW(Executor(small, 2, {.dispatch_cost_ms = std::nan("")}), std::invalid_argument);
}

TEST(Executor, RecordsOneTimingSamplePerFrame) {
  const FrameGraph graph({make_system("a", {}, {"x"}, [](const FrameContext&) {}),
                          make_system("b", {"x"}, {}, [](const FrameContext&) {})});
  Executor ex(graph, 2);
  constexpr size_t kFrames = 40;
  for (size_t f = 0; f < kFrames; ++f) ex.run_frame({f, 0, 0});
  ASSERT_EQ(ex.timings().size(), 2u);
  EXPECT_EQ(ex.timings()[0].name, "a");
  EXPECT_EQ(ex.timings()[1].name, "b");
  for (const SystemTiming& t : ex.timings()) {
    EXPECT_EQ(t.samples_ms.size(), kFrames) << t.name;
    EXPECT_GE(t.p50_ms(), 0.0);
    EXPECT_LE(t.p50_ms(), t.p99_ms());
  }
  EXPECT_EQ(ex.frame_timing().samples_ms.size(), kFrames);
  ex.clear_timings();
  EXPECT_TRUE(ex.frame_timing().samples_ms.empty());
  EXPECT_TRUE(ex.timings()[0].samples_ms.empty());
}

TEST(Executor, PercentilesUseNearestRank) {
  SystemTiming t;
  EXPECT_EQ(t.p50_ms(), 0.0);
  for (int i = 100; i >= 1; --i) t.samples_ms.push_back(static_cast<float>(i));
  EXPECT_EQ(t.p50_ms(), 50.0);
  EXPECT_EQ(t.p99_ms(), 99.0);
  EXPECT_EQ(t.percentile_ms(100), 100.0);
  EXPECT_EQ(t.percentile_ms(0), 1.0);
  EXPECT_EQ(t.percentile_ms(50.5), 51.0);
}

TEST(Executor, SystemExceptionReachesCallerAndExecutorRecoversOnASerialFrame) {
  int calls = 0;
  const FrameGraph graph({make_system("a", {}, {"x"}, [&](const FrameContext&) {
    if (++calls == 2) throw std::runtime_error("boom");
  })});
  Executor ex(graph, 2, {.access_check = AccessCheck::On, .dispatch = Dispatch::Serial});
  ex.run_frame({});
  EXPECT_THROW(ex.run_frame({}), std::runtime_error);
  ex.run_frame({});
  EXPECT_EQ(calls, 3);
}

TEST(Executor, SystemExceptionReachesCallerAndExecutorRecovers) {
  std::atomic<int> runs_a{0}, runs_b{0}, runs_c{0};
  const FrameGraph graph({make_system("a", {}, {"x"}, [&](const FrameContext&) { ++runs_a; }),
                          make_system("b", {"x"}, {"y"},
                                      [&](const FrameContext& ctx) {
                                        ++runs_b;
                                        if (ctx.frame == 1)
                                          throw std::runtime_error("mesh went bad");
                                      }),
                          make_system("c", {"y"}, {}, [&](const FrameContext&) { ++runs_c; })});
  Executor ex(graph, 2, AccessCheck::On);
  ex.run_frame({0, 0, 0});
  EXPECT_THROW(ex.run_frame({1, 0, 0}), std::runtime_error);
  EXPECT_EQ(runs_c.load(), 1);  // c depends on b, which failed
  ex.run_frame({2, 0, 0});
  ex.run_frame({3, 0, 0});
  EXPECT_EQ(runs_a.load(), 4);
  EXPECT_EQ(runs_b.load(), 4);
  EXPECT_EQ(runs_c.load(), 3);
}

TEST(Executor, RejectsNonPositiveThreadCount) {
  const FrameGraph graph({});
  EXPECT_THROW(Executor(graph, 0), std::invalid_argument);
  Executor ex(graph, 1, AccessCheck::Off);
  EXPECT_FALSE(ex.checks_access());
  ex.run_frame({});
  EXPECT_EQ(ex.frame_timing().samples_ms.size(), 1u);
}

TEST(Executor, ParallelForInsideSystemUsesTheExecutorsWorkers) {
  for (int threads : {1, 3}) {
    std::atomic<int> seen_workers{0};
    std::atomic<int> bad_worker{0};
    std::vector<int> out(10000, 0);
    const FrameGraph graph({make_system("fill", {}, {"out"}, [&](const FrameContext&) {
      seen_workers = worker_count();
      parallel_for(0, static_cast<uint32_t>(out.size()), 64, [&](uint32_t b, uint32_t e, int w) {
        if (w < 0 || w >= worker_count()) ++bad_worker;
        for (uint32_t i = b; i < e; ++i) out[i] += 1;
      });
    })});
    Executor ex(graph, threads);
    ex.run_frame({});
    EXPECT_EQ(seen_workers.load(), threads);
    EXPECT_EQ(bad_worker.load(), 0);
    EXPECT_EQ(std::count(out.begin(), out.end(), 1), static_cast<long>(out.size()));
  }
}

TEST(Executor, FrameAllocatesNothingOnOneThread) {
  if (!test::allocation_counting_available()) GTEST_SKIP() << "operator new is the sanitizer's";
  std::vector<float> data(4096, 1.0f);
  float total = 0;
  auto systems = test::random_systems(20, 6, 5);
  for (auto& s : systems) s.run = [](const FrameContext&) {};
  systems.push_back(make_system("reduce", {"data"}, {"total"}, [&](const FrameContext&) {
    total = parallel_reduce_ordered(
        0, 4096, 256, 0.0f,
        [&](uint32_t b, uint32_t e) {
          float s = 0;
          for (uint32_t i = b; i < e; ++i) s += data[i];
          return s;
        },
        [](float a, float b) { return a + b; });
  }));
  const FrameGraph graph(systems);
  // One thread keeps the count independent of when a TBB worker first joins; 2 and 4 threads
  // measured zero as well, but that rests on TBB internals this test should not pin down.
  Executor ex(graph, 1, AccessCheck::Off);
  for (int f = 0; f < 5; ++f) ex.run_frame({});  // let TBB set up its per-thread pools
  test::start_counting_allocations();
  for (int f = 0; f < 50; ++f) ex.run_frame({});
  test::stop_counting_allocations();
  EXPECT_EQ(test::allocations_counted(), 0);
  EXPECT_EQ(total, 4096.0f);
}

}  // namespace
}  // namespace phaco
