#pragma once
// Closed boxes as render::BodyView triangles, for the renderer's tests: exact geometry whose
// thickness along z and whose walls are known.
#include <cstdint>

#include "engine/render/snapshot.hpp"

namespace phaco::test {

// Appends the axis-aligned box [lo, hi] to b: 8 vertices, 12 triangles counter-clockwise seen from
// outside.
inline void add_box(render::BodyView& b, const Vec3& lo, const Vec3& hi) {
  const uint32_t base = static_cast<uint32_t>(b.xyz.size() / 3);
  for (int k = 0; k < 8; ++k) {  // corner bits: 1 = x, 2 = y, 4 = z at hi
    b.xyz.push_back(static_cast<float>((k & 1) ? hi.x() : lo.x()));
    b.xyz.push_back(static_cast<float>((k & 2) ? hi.y() : lo.y()));
    b.xyz.push_back(static_cast<float>((k & 4) ? hi.z() : lo.z()));
  }
  const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& q : quads)
    for (uint32_t i : {q[0], q[1], q[2], q[0], q[2], q[3]}) b.tris.push_back(base + i);
}

}  // namespace phaco::test
