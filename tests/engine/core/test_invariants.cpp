// The predicates behind the debug-build asserts (engine/core/invariants.hpp). The asserts are
// compiled out in Release, the predicates are not: they must say false exactly where the state
// is wrong, whatever the build.
#include <gtest/gtest.h>

#include <array>
#include <vector>

#include "engine/core/invariants.hpp"

namespace phaco {
namespace {

TEST(Invariants, SameSizeComparesEverySpanWithTheFirst) {
  const std::vector<float> x(4), y(4), z(3);
  const std::vector<uint8_t> alive(4);
  EXPECT_TRUE(same_size(x, y, alive));
  EXPECT_FALSE(same_size(x, y, z)) << "the last span is one short";
  EXPECT_FALSE(same_size(z, x, y)) << "the first span is one short";
  EXPECT_TRUE(same_size(x)) << "one span is always in step with itself";
}

TEST(Invariants, AllBelowNamesIndicesPastTheTable) {
  const std::vector<uint32_t> ids = {0, 3, 2};
  EXPECT_TRUE(all_below(ids, 4));
  EXPECT_FALSE(all_below(ids, 3)) << "3 is past a table of 3";
  EXPECT_TRUE(all_below({}, 0)) << "no index names nothing";
  const std::array<uint32_t, 4> tet = {5, 1, 2, kInvalidIndex};
  EXPECT_FALSE(all_below(tet, 6)) << "kInvalidIndex is past every table";
}

TEST(Invariants, LiveAllBelowSkipsTombstonesOnly) {
  // Three triangles over four particles; the dead one may keep any index.
  SlotIndex slots;
  slots.append(3);
  std::vector<uint32_t> a = {0, 1, 9}, b = {1, 2, 3}, c = {2, 3, 0};
  EXPECT_FALSE(live_all_below(slots, {a, b, c}, 4)) << "live triangle 2 names particle 9";
  slots.release(2);
  EXPECT_TRUE(live_all_below(slots, {a, b, c}, 4)) << "triangle 2 is a tombstone";
  EXPECT_FALSE(live_all_below(slots, {a, b, c}, 3)) << "live triangle 1 names particle 3";
  const std::vector<uint32_t> short_column = {0, 1};
  EXPECT_FALSE(live_all_below(slots, {a, short_column}, 4)) << "a column shorter than its slots";
}

}  // namespace
}  // namespace phaco
