#pragma once
// Predicates for debug-build asserts (issue 22, Box2D's practice): where a wrong size or index
// would not fail at once but corrupt state silently (a span shorter than its siblings read past
// its end, an index past a table that reads another element), functions assert these. Release
// and the sanitizer builds define NDEBUG, so the asserts and their O(n) walks cost nothing
// there and never change a result.
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <span>

#include "engine/core/table.hpp"

namespace phaco {

// Every span has the first one's length: spans indexed alike (the columns x, y, z of one table).
template <class First, class... Rest>
bool same_size(const First& first, const Rest&... rest) {
  return ((std::size(rest) == std::size(first)) && ...);
}

// Every index names an element of a table of `size` elements.
inline bool all_below(std::span<const uint32_t> indices, size_t size) {
  for (const uint32_t i : indices) {
    if (i >= size) return false;
  }
  return true;
}

// Every live element's index columns (a triangle's a, b, c) name elements of a table of `size`
// elements (its particles, tombstones included): what a cut or a compaction must leave behind.
inline bool live_all_below(const SlotIndex& slots,
                           std::initializer_list<std::span<const uint32_t>> columns, size_t size) {
  for (const std::span<const uint32_t> column : columns) {
    if (column.size() < slots.size()) return false;
    for (uint32_t e = 0; e < slots.size(); ++e) {
      if (slots.alive(e) && column[e] >= size) return false;
    }
  }
  return true;
}

}  // namespace phaco
