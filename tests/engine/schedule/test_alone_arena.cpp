#include <gtest/gtest.h>
#include <oneapi/tbb/task_arena.h>

#include <bit>
#include <mutex>
#include <set>
#include <thread>
#include <utility>
#include <vector>

#include "engine/schedule/alone_arena.hpp"
#include "engine/schedule/parallel.hpp"
#include "tests/engine/schedule/order_sensitive.hpp"

namespace phaco {
namespace {

uint32_t ordered_sum_bits(const std::vector<float>& x) {
  const float s = parallel_reduce_ordered(
      0, uint32_t(x.size()), 257, 0.0f,
      [&](uint32_t b, uint32_t e) {
        float part = 0;
        for (uint32_t i = b; i < e; ++i) part += x[i];
        return part;
      },
      [](float a, float b) { return a + b; });
  return std::bit_cast<uint32_t>(s);
}

TEST(AloneArena, KeepsEveryNestedLoopOnTheCallingThread) {
  tbb::task_arena two(2);
  AloneArena alone;
  two.execute([&] {
    ASSERT_EQ(worker_count(), 2);
    const std::thread::id caller = std::this_thread::get_id();
    std::set<std::thread::id> ran_on;
    std::mutex m;
    int inside = 0;
    for (int round = 0; round < 3; ++round)  // the arena is made once and reused
      alone.run([&] {
        inside = worker_count();
        parallel_for(0, 100000, 64, [&](uint32_t, uint32_t, int) {
          std::lock_guard lock(m);
          ran_on.insert(std::this_thread::get_id());
        });
      });
    EXPECT_EQ(inside, 1);
    ASSERT_EQ(ran_on.size(), 1u);
    EXPECT_EQ(*ran_on.begin(), caller);
    EXPECT_EQ(worker_count(), 2);  // back in the pool of two afterwards
  });
}

TEST(AloneArena, GivesTheSameBitsAsThePoolOfTwo) {
  const std::vector<float> x = test::order_sensitive_values(50021, 777);
  uint32_t pooled = 0, alone_bits = 0;
  tbb::task_arena two(2);
  AloneArena alone;
  two.execute([&] {
    pooled = ordered_sum_bits(x);
    alone.run([&] { alone_bits = ordered_sum_bits(x); });
  });
  EXPECT_EQ(alone_bits, pooled);
  // The check can fail: a left-to-right sum of the same values rounds to other bits.
  EXPECT_NE(std::bit_cast<uint32_t>(test::linear_sum(x)), pooled);
}

TEST(AloneArena, RunsDirectlyOnOneThreadAndSurvivesAMove) {
  tbb::task_arena one(1);
  AloneArena first;
  one.execute([&] {
    int calls = 0;
    first.run([&] { ++calls; });
    EXPECT_EQ(calls, 1);
  });
  tbb::task_arena two(2);
  two.execute([&] {
    first.run([] {});  // made here
    AloneArena moved = std::move(first);
    int inside = 0;
    moved.run([&] { inside = worker_count(); });
    EXPECT_EQ(inside, 1);
  });
}

}  // namespace
}  // namespace phaco
