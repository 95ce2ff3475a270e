#pragma once
// Surface triangles of a body, by particle index (counter-clockwise seen from outside / from +z).
#include <cstdint>
#include <vector>

#include "engine/core/table.hpp"

namespace phaco {

struct Triangles {
  SlotIndex slots;
  std::vector<uint32_t> a, b, c;  // particle indices

  template <class F>
  void for_each_column(F&& f) {
    f(a), f(b), f(c);
  }
};

}  // namespace phaco
