#pragma once
// Test support: small hand-made meshes around vertex 0 for the vertex-manifoldness checks
// (engine/core/mesh_checks' check_surface and systems/topology_check's check_membrane). Each says
// how many fans its vertex 0 has; every other vertex has one, and no edge has more than two
// triangles, so a mesh with one fan at vertex 0 is a manifold (with boundary).
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>
#include <vector>

#include "engine/core/mesh_data.hpp"

namespace phaco::test {

struct FanMesh {
  std::string name;
  SurfaceMesh mesh;
  uint32_t fans_at_0;            // triangle fans around vertex 0
  uint32_t second_fan_triangle;  // lowest triangle outside the fan of triangle 0 (if fans_at_0 > 1)
};

// n triangles around vertex 0 at `centre`, rim points on a circle of radius 1 in the plane
// z = centre.z + dz from angle a0 through `sweep` radians; closed (a disc) when the sweep is 2π.
// Counter-clockwise seen from +z. Appends to `m`.
inline void add_fan(SurfaceMesh& m, int n, double a0, double sweep, double dz) {
  const bool closed = std::abs(sweep - 2.0 * std::numbers::pi) < 1e-12;
  const auto first = static_cast<uint32_t>(m.vertices.size());
  const int rim = closed ? n : n + 1;
  for (int k = 0; k < rim; ++k) {
    const double a = a0 + sweep * k / n;
    m.vertices.emplace_back(std::cos(a), std::sin(a), dz);
  }
  for (int k = 0; k < n; ++k) {
    const uint32_t b = first + static_cast<uint32_t>(k);
    const uint32_t c = first + static_cast<uint32_t>((k + 1) % rim);
    m.triangles.push_back({0u, b, c});
  }
}

inline std::vector<FanMesh> fan_meshes() {
  constexpr double kPi = std::numbers::pi;
  std::vector<FanMesh> out;
  auto make = [&](const char* name, uint32_t fans, uint32_t second, auto&& build) {
    SurfaceMesh m;
    m.vertices.emplace_back(0.0, 0.0, 0.0);
    build(m);
    out.push_back({name, std::move(m), fans, second});
  };
  make("disc (interior vertex, six triangles)", 1, 0,
       [](SurfaceMesh& m) { add_fan(m, 6, 0.0, 2.0 * kPi, 0.0); });
  make("half-disc (boundary vertex, three triangles)", 1, 0,
       [](SurfaceMesh& m) { add_fan(m, 3, 0.0, kPi, 0.0); });
  make("bowtie (two triangles sharing only vertex 0)", 2, 1, [](SurfaceMesh& m) {
    add_fan(m, 1, 0.0, 0.5 * kPi, 0.0);
    add_fan(m, 1, kPi, 0.5 * kPi, 0.0);
  });
  make("two boundary fans (two half-discs of two triangles meeting at vertex 0)", 2, 2,
       [](SurfaceMesh& m) {
         add_fan(m, 2, 0.0, 0.75 * kPi, 0.0);
         add_fan(m, 2, kPi, 0.75 * kPi, 0.0);
       });
  make("three boundary fans", 3, 1, [](SurfaceMesh& m) {
    add_fan(m, 1, 0.0, 0.5 * kPi, 0.0);
    add_fan(m, 1, 0.7 * kPi, 0.5 * kPi, 0.0);
    add_fan(m, 1, 1.4 * kPi, 0.5 * kPi, 0.0);
  });
  // Both fans closed: vertex 0 is interior to each cone, so no boundary edge touches it, and only
  // the fans themselves show the bowtie.
  make("two discs (a double cone with its apex at vertex 0)", 2, 5, [](SurfaceMesh& m) {
    add_fan(m, 5, 0.0, 2.0 * kPi, 1.0);
    add_fan(m, 5, 0.0, 2.0 * kPi, -1.0);
  });
  make("a disc and a triangle touching it at its centre", 2, 6, [](SurfaceMesh& m) {
    add_fan(m, 6, 0.0, 2.0 * kPi, 0.0);
    add_fan(m, 1, 0.0, 0.5 * kPi, 1.0);
  });
  return out;
}

}  // namespace phaco::test
