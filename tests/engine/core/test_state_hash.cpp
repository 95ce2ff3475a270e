#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "engine/core/state_hash.hpp"

namespace phaco {
namespace {

uint64_t hash_of(const std::vector<float>& v) {
  StateHash h;
  h.add(std::span<const float>(v));
  return h.value();
}

TEST(StateHash, EqualForEqualBitsDifferentOtherwise) {
  const std::vector<float> a = {1.0f, 2.0f, 3.0f};
  EXPECT_EQ(hash_of(a), hash_of(a));
  std::vector<float> b = a;
  b[2] = std::nextafter(3.0f, 4.0f);  // one ulp
  EXPECT_NE(hash_of(a), hash_of(b));
  EXPECT_NE(hash_of({0.0f}), hash_of({-0.0f})) << "bit-identical means signed zeros differ";
  EXPECT_NE(hash_of({1.0f, 2.0f}), hash_of({2.0f, 1.0f})) << "order matters";
  EXPECT_NE(hash_of({}), hash_of({0.0f})) << "length matters";
}

TEST(StateHash, HexIsSixteenDigits) {
  StateHash h;
  h.add_string("capsule");
  EXPECT_EQ(h.hex().size(), 16u);
}

}  // namespace
}  // namespace phaco
