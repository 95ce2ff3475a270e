#pragma once
// Tetrahedra of a volumetric body (the lens), by particle index, positively oriented.
#include <array>
#include <cstdint>
#include <vector>

#include "engine/core/table.hpp"

namespace phaco {

// Face k of a positively oriented tet (a, b, c, d) is the face opposite local vertex k; its
// corners, counter-clockwise seen from outside the tet:
//   0: (b, c, d)   1: (a, d, c)   2: (a, b, d)   3: (a, c, b)
inline constexpr std::array<std::array<uint8_t, 3>, 4> kTetFaceCorners = {
    {{1, 2, 3}, {0, 3, 2}, {0, 1, 3}, {0, 2, 1}}};

struct Tets {
  SlotIndex slots;
  std::vector<uint32_t> a, b, c, d;  // particle indices
  std::vector<uint8_t> region;       // lens: 1 nucleus, 0 cortex

  template <class F>
  void for_each_column(F&& f) {
    f(a), f(b), f(c), f(d), f(region);
  }
};

}  // namespace phaco
