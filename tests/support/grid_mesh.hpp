#pragma once
// Test support: a flat n × n sheet at unit spacing in z = 0, interior vertices jittered by up to
// `jitter` (deterministic), quads split along alternating diagonals: quad (i, j) is cut along
// (i, j)-(i+1, j+1) when i + j is even, else along (i+1, j)-(i, j+1). Vertex (i, j) is j·n + i.
#include <cmath>

#include "engine/core/mesh_data.hpp"

namespace phaco::test {

inline SurfaceMesh grid_mesh(int n, double jitter) {
  SurfaceMesh m;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const bool rim = i == 0 || j == 0 || i == n - 1 || j == n - 1;
      const double jx = rim ? 0.0 : jitter * std::sin(12.9898 * i + 78.233 * j);
      const double jy = rim ? 0.0 : jitter * std::sin(39.3468 * i + 11.135 * j + 1.0);
      m.vertices.emplace_back(i + jx, j + jy, 0.0);
    }
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      const uint32_t v00 = j * n + i, v10 = v00 + 1, v01 = v00 + n, v11 = v01 + 1;
      if ((i + j) % 2 == 0) {
        m.triangles.push_back({v00, v10, v11});
        m.triangles.push_back({v00, v11, v01});
      } else {
        m.triangles.push_back({v00, v10, v01});
        m.triangles.push_back({v10, v11, v01});
      }
    }
  return m;
}

}  // namespace phaco::test
