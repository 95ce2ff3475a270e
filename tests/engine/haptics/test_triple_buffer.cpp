// TripleBuffer: newest-wins semantics on one thread, and no torn or backward read under a
// producer and a consumer running flat out.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <set>
#include <thread>

#include "engine/haptics/triple_buffer.hpp"

namespace phaco {
namespace {

TEST(TripleBuffer, NewestWinsAndAcquireIsFalseWhenNothingNew) {
  TripleBuffer<int> buffer;
  EXPECT_FALSE(buffer.acquire());
  EXPECT_EQ(buffer.read_slot(), 0);  // value-initialised

  buffer.write_slot() = 1;
  buffer.publish();
  EXPECT_TRUE(buffer.acquire());
  EXPECT_EQ(buffer.read_slot(), 1);
  EXPECT_FALSE(buffer.acquire());
  EXPECT_EQ(buffer.read_slot(), 1);

  // Two publishes before the consumer looks: only the newest is seen.
  buffer.write_slot() = 2;
  buffer.publish();
  buffer.write_slot() = 3;
  buffer.publish();
  EXPECT_TRUE(buffer.acquire());
  EXPECT_EQ(buffer.read_slot(), 3);
  EXPECT_FALSE(buffer.acquire());
  EXPECT_EQ(buffer.read_slot(), 3);
}

TEST(TripleBuffer, WriterNeverWritesTheSlotTheReaderHolds) {
  struct Wide {
    std::array<double, 100> v{};
  };
  TripleBuffer<Wide> buffer;
  std::set<const Wide*> seen;
  for (int step = 0; step < 50; ++step) {
    EXPECT_NE(&buffer.write_slot(), &buffer.read_slot());
    EXPECT_EQ(reinterpret_cast<std::uintptr_t>(&buffer.write_slot()) % 64, 0u);  // cache-aligned
    seen.insert(&buffer.write_slot());
    seen.insert(&buffer.read_slot());
    buffer.write_slot().v[0] = step;
    buffer.publish();
    if (step % 3 == 0) {
      EXPECT_TRUE(buffer.acquire());
      EXPECT_EQ(buffer.read_slot().v[0], step);
    }
  }
  EXPECT_EQ(seen.size(), 3u);  // exactly three slots, reused, never reallocated
}

// A slot the consumer reads must be the one whole publish: every word derived from one counter.
struct Pattern {
  uint64_t counter = 0;
  std::array<uint64_t, 1024> words{};  // 8 KiB
};

uint64_t word(uint64_t counter, std::size_t i) {
  return counter * 0x9E3779B97F4A7C15ULL + i;
}

TEST(TripleBuffer, TwoThreadsNoTornReadAndCountersNeverGoBackwards) {
  constexpr uint64_t kPublishes = 5000;
  TripleBuffer<Pattern> buffer;

  std::thread producer([&] {
    for (uint64_t c = 1; c <= kPublishes; ++c) {
      Pattern& slot = buffer.write_slot();
      slot.counter = c;
      for (std::size_t i = 0; i < slot.words.size(); ++i) slot.words[i] = word(c, i);
      buffer.publish();
    }
  });

  uint64_t last = 0;
  uint64_t acquired = 0;
  uint64_t torn = 0;
  uint64_t backwards = 0;
  while (last < kPublishes) {
    if (!buffer.acquire()) continue;
    const Pattern& slot = buffer.read_slot();
    ++acquired;
    if (slot.counter <= last) ++backwards;  // acquire true means a newer publish
    for (std::size_t i = 0; i < slot.words.size(); ++i)
      if (slot.words[i] != word(slot.counter, i)) {
        ++torn;
        break;
      }
    last = slot.counter;
  }
  producer.join();

  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(backwards, 0u);
  EXPECT_EQ(last, kPublishes);  // the final publish always arrives
  EXPECT_GE(acquired, 1u);
  EXPECT_FALSE(buffer.acquire());
}

}  // namespace
}  // namespace phaco
