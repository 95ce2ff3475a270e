#pragma once
// Tetrahedra of a volumetric body (the lens), by particle index, positively oriented.
#include <cstdint>
#include <vector>

#include "engine/core/table.hpp"

namespace phaco {

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
