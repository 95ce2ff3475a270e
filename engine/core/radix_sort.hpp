#pragma once
// Sorts 32-bit indices in linear time: LSD radix sort, 11 bits per pass, skipping the passes above
// the largest key. For the lists a frame sorts (the active set's particles and springs, a few
// thousand to tens of thousands of indices below 2²²) that is two passes, several times cheaper
// than std::sort's n·log n comparisons. The result is the same sequence std::sort gives.
//
// Allocates only when `scratch` has to grow (keep it between calls).
#include <algorithm>
#include <array>
#include <bit>
#include <cstdint>
#include <utility>
#include <vector>

namespace phaco {

inline void radix_sort_indices(std::vector<uint32_t>& keys, std::vector<uint32_t>& scratch) {
  constexpr int kBits = 11;
  constexpr uint32_t kMask = (1u << kBits) - 1;
  const size_t n = keys.size();
  if (n < 512) {  // a pass's 2048 counters would cost more than the comparisons
    std::sort(keys.begin(), keys.end());
    return;
  }
  uint32_t all_or = 0;
  for (uint32_t k : keys) all_or |= k;
  const int bits = 32 - std::countl_zero(all_or);
  scratch.resize(n);
  uint32_t *from = keys.data(), *to = scratch.data();
  std::array<uint32_t, kMask + 1> count;
  for (int shift = 0; shift < bits; shift += kBits) {
    count.fill(0);
    for (size_t i = 0; i < n; ++i) ++count[(from[i] >> shift) & kMask];
    if (count[(from[0] >> shift) & kMask] == n) continue;  // one digit: nothing moves
    uint32_t sum = 0;
    for (uint32_t& c : count) {
      const uint32_t here = c;
      c = sum;
      sum += here;
    }
    for (size_t i = 0; i < n; ++i) to[count[(from[i] >> shift) & kMask]++] = from[i];
    std::swap(from, to);
  }
  // The sorted keys end in `keys` itself (its buffer is the caller's: never swapped away).
  if (from != keys.data()) std::copy(from, from + n, keys.data());
}

}  // namespace phaco
