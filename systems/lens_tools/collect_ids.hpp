#pragma once
// Sorted list of the indices in [0, n) that satisfy a predicate, built in parallel without
// allocation once the scratch is warm. Fixed chunks of kCollectChunk indices: each chunk writes its
// hits into scratch_ids from its own first index (so chunks never share memory) and counts them;
// the runs are then packed in chunk order, which keeps the list sorted for any thread count.
#include <algorithm>
#include <cstdint>
#include <vector>

#include "engine/schedule/parallel.hpp"

namespace phaco::lens_tools::detail {

inline constexpr uint32_t kCollectChunk = 4096;

template <class Pred>
void collect_ids(uint32_t n, std::vector<uint32_t>& scratch_ids,
                 std::vector<uint32_t>& scratch_counts, std::vector<uint32_t>& out, Pred&& pred) {
  out.clear();
  if (n == 0) return;
  const uint32_t chunks = (n + kCollectChunk - 1) / kCollectChunk;
  if (scratch_ids.size() < n) scratch_ids.resize(n);
  if (scratch_counts.size() < chunks) scratch_counts.resize(chunks);
  uint32_t* ids = scratch_ids.data();
  uint32_t* counts = scratch_counts.data();
  parallel_for(0, chunks, 1, [&](uint32_t cb, uint32_t ce, int) {
    for (uint32_t c = cb; c < ce; ++c) {
      const uint32_t b = c * kCollectChunk, e = std::min(n, b + kCollectChunk);
      uint32_t k = b;
      for (uint32_t i = b; i < e; ++i)
        if (pred(i)) ids[k++] = i;
      counts[c] = k - b;
    }
  });
  uint32_t total = 0;
  for (uint32_t c = 0; c < chunks; ++c) total += counts[c];
  out.resize(total);
  uint32_t at = 0;
  for (uint32_t c = 0; c < chunks; ++c) {
    std::copy_n(ids + c * kCollectChunk, counts[c], out.data() + at);
    at += counts[c];
  }
}

}  // namespace phaco::lens_tools::detail
