// SpscRing: FIFO order and exactly-once delivery across two threads; a full ring refuses and
// counts the drop.
#include <gtest/gtest.h>

#include <cstdint>
#include <thread>
#include <vector>

#include "engine/haptics/spsc_ring.hpp"

namespace phaco {
namespace {

TEST(SpscRing, FullRefusesAndCountsTheDrop) {
  SpscRing<int, 4> ring;
  EXPECT_EQ(ring.capacity(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_EQ(ring.size_approx(), 4u);
  EXPECT_FALSE(ring.try_push(99));
  EXPECT_FALSE(ring.try_push(100));
  EXPECT_EQ(ring.dropped(), 2u);

  int out = -1;
  ASSERT_TRUE(ring.try_pop(out));
  EXPECT_EQ(out, 0);
  EXPECT_TRUE(ring.try_push(4));  // room again
  EXPECT_EQ(ring.dropped(), 2u);

  std::vector<int> rest;
  EXPECT_EQ(ring.drain([&](const int& v) { rest.push_back(v); }), 4u);
  EXPECT_EQ(rest, (std::vector<int>{1, 2, 3, 4}));
  EXPECT_FALSE(ring.try_pop(out));
  EXPECT_EQ(ring.size_approx(), 0u);
}

TEST(SpscRing, WrapsAroundManyTimesInOrder) {
  SpscRing<uint32_t, 8> ring;
  uint32_t next_in = 0, next_out = 0;
  for (int round = 0; round < 1000; ++round) {
    const int n = 1 + round % 8;
    for (int i = 0; i < n; ++i) ASSERT_TRUE(ring.try_push(next_in++));
    uint32_t v = 0;
    while (ring.try_pop(v)) ASSERT_EQ(v, next_out++);
  }
  EXPECT_EQ(next_in, next_out);
  EXPECT_EQ(ring.dropped(), 0u);
}

TEST(SpscRing, TwoThreadsEveryValueOnceInOrder) {
  constexpr uint64_t kValues = 300'000;
  SpscRing<uint64_t, 64> ring;  // small, so the producer often finds it full
  uint64_t refused = 0;

  std::thread producer([&] {
    for (uint64_t v = 0; v < kValues; ++v)
      while (!ring.try_push(v)) {
        ++refused;
        std::this_thread::yield();
      }
  });

  uint64_t expected = 0;
  uint64_t out_of_order = 0;
  while (expected < kValues) {
    uint64_t v = 0;
    if (!ring.try_pop(v)) continue;
    if (v != expected) ++out_of_order;
    expected = v + 1;
  }
  producer.join();

  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(expected, kValues);
  uint64_t extra = 0;
  EXPECT_FALSE(ring.try_pop(extra));   // nothing delivered twice
  EXPECT_EQ(ring.dropped(), refused);  // every refused push counted, none else
}

}  // namespace
}  // namespace phaco
