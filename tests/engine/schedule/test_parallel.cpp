#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <algorithm>
#include <atomic>
#include <bit>
#include <mutex>
#include <utility>
#include <vector>

#include "engine/schedule/parallel.hpp"
#include "tests/engine/schedule/order_sensitive.hpp"

namespace phaco {
namespace {

using Chunks = std::vector<std::pair<uint32_t, uint32_t>>;

Chunks chunks_of(int threads, uint32_t begin, uint32_t end, uint32_t grain, bool* workers_ok) {
  Chunks chunks;
  std::mutex m;
  tbb::task_arena arena(threads);
  arena.execute([&] {
    EXPECT_EQ(worker_count(), threads);
    parallel_for(begin, end, grain, [&](uint32_t b, uint32_t e, int worker) {
      std::lock_guard lock(m);
      chunks.emplace_back(b, e);
      if (worker < 0 || worker >= threads) *workers_ok = false;
    });
  });
  std::sort(chunks.begin(), chunks.end());
  return chunks;
}

// The split tbb::simple_partitioner makes on a blocked_range: halve until size <= grain.
void reference_chunks(uint32_t b, uint32_t e, uint32_t grain, Chunks& out) {
  if (e - b > grain) {
    const uint32_t mid = b + (e - b) / 2;
    reference_chunks(b, mid, grain, out);
    reference_chunks(mid, e, grain, out);
  } else {
    out.emplace_back(b, e);
  }
}

TEST(ParallelFor, CoversTheRangeExactlyOnce) {
  constexpr uint32_t kBegin = 13, kEnd = 10007;
  std::vector<std::atomic<int>> hits(kEnd);
  for (auto& h : hits) h = 0;
  tbb::task_arena arena(4);
  arena.execute([&] {
    parallel_for(kBegin, kEnd, 37, [&](uint32_t b, uint32_t e, int) {
      for (uint32_t i = b; i < e; ++i) ++hits[i];
    });
  });
  for (uint32_t i = 0; i < kEnd; ++i) ASSERT_EQ(hits[i].load(), i < kBegin ? 0 : 1) << i;
}

TEST(ParallelFor, ChunksDependOnlyOnRangeAndGrain) {
  bool workers_ok = true;
  const Chunks one = chunks_of(1, 5, 5005, 64, &workers_ok);
  const Chunks two = chunks_of(2, 5, 5005, 64, &workers_ok);
  const Chunks four = chunks_of(4, 5, 5005, 64, &workers_ok);
  EXPECT_TRUE(workers_ok);
  EXPECT_EQ(one, two);
  EXPECT_EQ(one, four);
  Chunks expected;
  reference_chunks(5, 5005, 64, expected);
  EXPECT_EQ(one, expected);
  // The chunks tile the range, each at most `grain` long.
  uint32_t at = 5;
  for (const auto& [b, e] : one) {
    EXPECT_EQ(b, at);
    EXPECT_GT(e, b);
    EXPECT_LE(e - b, 64u);
    at = e;
  }
  EXPECT_EQ(at, 5005u);
}

TEST(ParallelFor, EmptyRangeAndZeroGrain) {
  int calls = 0;
  parallel_for(7, 7, 4, [&](uint32_t, uint32_t, int) { ++calls; });
  parallel_for(9, 3, 4, [&](uint32_t, uint32_t, int) { ++calls; });
  EXPECT_EQ(calls, 0);
  bool workers_ok = true;
  const Chunks singles = chunks_of(2, 0, 10, 0, &workers_ok);
  ASSERT_EQ(singles.size(), 10u);
  for (uint32_t i = 0; i < 10; ++i)
    EXPECT_EQ(singles[i], (std::pair<uint32_t, uint32_t>{i, i + 1}));
}

// Same tree as parallel_reduce_ordered, computed serially.
float reference_tree_sum(const std::vector<float>& x, uint32_t b, uint32_t e, uint32_t grain) {
  if (e - b > grain) {
    const uint32_t mid = b + (e - b) / 2;
    return reference_tree_sum(x, b, mid, grain) + reference_tree_sum(x, mid, e, grain);
  }
  float s = 0;
  for (uint32_t i = b; i < e; ++i) s += x[i];
  return s;
}

TEST(ParallelReduceOrdered, FloatSumIsBitIdenticalForAnyThreadCount) {
  // Wide dynamic range so that any change of summation order changes the rounded result.
  const std::vector<float> x = test::order_sensitive_values(100003, 12345);
  const uint32_t n = static_cast<uint32_t>(x.size());
  auto sum_with = [&](int threads) {
    float result = 0;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      result = parallel_reduce_ordered(
          0, n, 500, 0.0f,
          [&](uint32_t b, uint32_t e) {
            float s = 0;
            for (uint32_t i = b; i < e; ++i) s += x[i];
            return s;
          },
          [](float a, float b) { return a + b; });
    });
    return std::bit_cast<uint32_t>(result);
  };
  const uint32_t one = sum_with(1);
  EXPECT_EQ(sum_with(2), one);
  EXPECT_EQ(sum_with(4), one);
  EXPECT_EQ(std::bit_cast<uint32_t>(0.0f + reference_tree_sum(x, 0, n, 500)), one);
  // The data is order-sensitive: a plain left-to-right sum rounds differently.
  EXPECT_NE(std::bit_cast<uint32_t>(test::linear_sum(x)), one);
}

TEST(ParallelReduceOrdered, KeepsChunkOrderForNonCommutativeMerge) {
  using List = std::vector<uint32_t>;
  auto concat = [](List a, List b) {
    a.insert(a.end(), b.begin(), b.end());
    return a;
  };
  for (int threads : {1, 2, 4}) {
    List order;
    tbb::task_arena arena(threads);
    arena.execute([&] {
      order = parallel_reduce_ordered(
          0, 1000, 16, List{999999}, [](uint32_t b, uint32_t) { return List{b}; }, concat);
    });
    Chunks chunks;
    reference_chunks(0, 1000, 16, chunks);
    ASSERT_EQ(order.size(), chunks.size() + 1) << threads;
    EXPECT_EQ(order[0], 999999u);  // init first
    for (size_t k = 0; k < chunks.size(); ++k) EXPECT_EQ(order[k + 1], chunks[k].first);
  }
}

TEST(ParallelReduceOrdered, EmptyRangeReturnsInit) {
  const int r = parallel_reduce_ordered(
      4, 4, 8, 42, [](uint32_t, uint32_t) { return 1; }, [](int a, int b) { return a + b; });
  EXPECT_EQ(r, 42);
}

}  // namespace
}  // namespace phaco
