// radix_sort_indices gives std::sort's order for every size and key range a frame sorts, and
// leaves the result in the caller's buffer.
#include <gtest/gtest.h>

#include <algorithm>
#include <vector>

#include "engine/core/radix_sort.hpp"
#include "engine/core/rng.hpp"

namespace phaco {
namespace {

TEST(RadixSortIndices, MatchesStdSortOverSizesAndKeyRanges) {
  const CounterRng rng(17);
  std::vector<uint32_t> scratch;
  uint64_t stream = 0;
  // Sizes below and above the comparison-sort cutoff; key ranges of one to three passes, and one
  // whose low digit is the same for every key (a pass skipped).
  for (uint32_t n : {0u, 1u, 7u, 511u, 512u, 3000u, 20000u})
    for (uint32_t bits : {4u, 11u, 12u, 22u, 32u})
      for (bool low_digit_fixed : {false, true}) {
        std::vector<uint32_t> keys(n);
        for (uint32_t i = 0; i < n; ++i) {
          const uint32_t r = rng.bits(stream, i)[0];
          keys[i] = bits == 32 ? r : r & ((1u << bits) - 1);
          if (low_digit_fixed) keys[i] = (keys[i] & ~0x7ffu) | 0x5u;
        }
        ++stream;
        std::vector<uint32_t> expected = keys;
        std::sort(expected.begin(), expected.end());
        const uint32_t* buffer = keys.data();
        radix_sort_indices(keys, scratch);
        EXPECT_EQ(keys, expected) << n << " keys of " << bits << " bits";
        EXPECT_EQ(keys.data(), buffer) << "sorted in the caller's buffer";
      }
}

}  // namespace
}  // namespace phaco
