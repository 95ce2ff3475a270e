#pragma once
// Cold mesh data as produced by generators and file readers, before a body turns it into flat
// per-element tables. Coordinates in mm (DESIGN.md §6 frame).
#include <array>
#include <cstdint>
#include <vector>

#include "engine/core/math.hpp"

namespace phaco {

struct SurfaceMesh {
  std::vector<Vec3> vertices;                      // mm
  std::vector<std::array<uint32_t, 3>> triangles;  // counter-clockwise seen from outside
};

struct TetMesh {
  std::vector<Vec3> vertices;                 // mm
  std::vector<std::array<uint32_t, 4>> tets;  // positive orientation: (b-a)·((c-a)×(d-a)) > 0
  std::vector<uint8_t> region;                // per tet; for the lens 1 = nucleus, 0 = cortex
};

}  // namespace phaco
