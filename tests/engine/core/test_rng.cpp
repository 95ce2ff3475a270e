#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "engine/core/rng.hpp"

namespace phaco {
namespace {

// Known-answer vectors of Random123 (kat_vectors, philox4x32 10).
TEST(Philox, KnownAnswers) {
  EXPECT_EQ((PhiloxCounter{0x6627e8d5, 0xe169c58d, 0xbc57ac4c, 0x9b00dbd8}),
            philox4x32_10({0, 0, 0, 0}, {0, 0}));
  EXPECT_EQ(
      (PhiloxCounter{0x408f276d, 0x41c83b0e, 0xa20bc7c6, 0x6d5451fd}),
      philox4x32_10({0xffffffff, 0xffffffff, 0xffffffff, 0xffffffff}, {0xffffffff, 0xffffffff}));
  EXPECT_EQ(
      (PhiloxCounter{0xd16cfe09, 0x94fdcceb, 0x5001e420, 0x24126ea1}),
      philox4x32_10({0x243f6a88, 0x85a308d3, 0x13198a2e, 0x03707344}, {0xa4093822, 0x299f31d0}));
}

TEST(CounterRng, PureFunctionOfItsCounter) {
  const CounterRng a(7), b(7);
  EXPECT_EQ(a.bits(3, 11), b.bits(3, 11));
  EXPECT_NE(a.bits(3, 11), a.bits(3, 12));
  EXPECT_NE(a.bits(3, 11), a.bits(4, 11));
  EXPECT_NE(a.bits(3, 11, 0), a.bits(3, 11, 1));
  EXPECT_NE(a.bits(3, 11), CounterRng(8).bits(3, 11));
  EXPECT_NE(a.bits(3, 11), CounterRng(7, 1).bits(3, 11)) << "streams are independent";
  // Large frame numbers use the high word.
  EXPECT_NE(a.bits(uint64_t{1} << 32, 0), a.bits(0, 0));
}

TEST(CounterRng, UniformMomentsAndRange) {
  const CounterRng rng(42);
  const int n = 200000;
  double sum = 0, sum2 = 0;
  for (int i = 0; i < n; ++i) {
    const float u = rng.uniform(1, static_cast<uint32_t>(i));
    ASSERT_GE(u, 0.0f);
    ASSERT_LT(u, 1.0f);
    sum += u;
    sum2 += double(u) * u;
  }
  const double mean = sum / n, var = sum2 / n - mean * mean;
  EXPECT_NEAR(mean, 0.5, 0.005);
  EXPECT_NEAR(var, 1.0 / 12.0, 0.002);
  const double d = rng.uniform_double(1, 5);
  EXPECT_GE(d, 0.0);
  EXPECT_LT(d, 1.0);
}

}  // namespace
}  // namespace phaco
