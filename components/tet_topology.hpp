#pragma once
// Face adjacency, liveness and the surface-tet list of a tetrahedral body (the lens) for
// sculpting (seed 000 §5.3: "the data structure of a tetrahedron registers its four neighbours";
// "a list of surface tetrahedrons is maintained ... internal tetrahedrons are exposed to become
// surface tetrahedrons").
//
// Neighbour k of tet t is the tet across the face opposite t's vertex k (kNoTet on the mesh
// boundary). A tet is a surface tet when it is alive and at least one of its faces has no alive
// neighbour. Removal never un-exposes a face, so a tet leaves the surface list only by being
// removed; the list is a dense array plus each tet's position in it, so both changes are O(1).
//
// Face k of a positively oriented tet (a, b, c, d), wound counter-clockwise seen from outside:
//   0: (b, c, d)   1: (a, d, c)   2: (a, b, d)   3: (a, c, b)
#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <stdexcept>
#include <utility>
#include <vector>

#include "components/tets.hpp"  // kTetFaceCorners
#include "engine/core/math.hpp"
#include "engine/core/mesh_data.hpp"

namespace phaco {

inline constexpr uint32_t kNoTet = 0xFFFFFFFFu;

struct TetTopology {
  // Per tet (index = TetMesh tet index).
  std::vector<std::array<uint32_t, 4>> vertices;    // mesh vertex indices, positive orientation
  std::vector<std::array<uint32_t, 4>> neighbours;  // across the face opposite vertex k, or kNoTet
  std::vector<uint8_t> alive;                       // 1 until sculpted away
  std::vector<float> centre_x, centre_y, centre_z;  // mm, centroid (inside the tet)
  std::vector<float> bound_radius;                  // mm, max centroid-to-vertex distance
  std::vector<float> volume;                        // mm³

  // Surface tets: dense list plus each tet's slot in it (kNoTet when not listed).
  std::vector<uint32_t> surface;
  std::vector<uint32_t> surface_slot;

  uint32_t tet_count = 0;
  uint32_t alive_count = 0;
};

inline bool tet_on_surface(const TetTopology& topo, uint32_t t) {
  if (!topo.alive[t]) return false;
  for (uint32_t n : topo.neighbours[t])
    if (n == kNoTet || !topo.alive[n]) return true;
  return false;
}

inline void surface_add(TetTopology& topo, uint32_t t) {
  if (topo.surface_slot[t] != kNoTet) return;
  topo.surface_slot[t] = static_cast<uint32_t>(topo.surface.size());
  topo.surface.push_back(t);
}

inline void surface_remove(TetTopology& topo, uint32_t t) {
  const uint32_t slot = topo.surface_slot[t];
  if (slot == kNoTet) return;
  const uint32_t last = topo.surface.back();
  topo.surface[slot] = last;
  topo.surface_slot[last] = slot;
  topo.surface.pop_back();
  topo.surface_slot[t] = kNoTet;
}

// Marks t dead and updates the surface list: t leaves it, its alive neighbours join it.
inline void remove_tet(TetTopology& topo, uint32_t t) {
  if (!topo.alive[t]) return;
  topo.alive[t] = 0;
  --topo.alive_count;
  surface_remove(topo, t);
  for (uint32_t n : topo.neighbours[t])
    if (n != kNoTet && topo.alive[n]) surface_add(topo, n);
}

// Builds the topology of a whole, all-alive mesh. Faces are matched by their sorted vertex triple
// in an open-addressing hash table (O(n), deterministic). Throws std::invalid_argument on a vertex
// index out of range or a face shared by more than two tets.
inline TetTopology build_tet_topology(const TetMesh& mesh) {
  TetTopology topo;
  const auto n = static_cast<uint32_t>(mesh.tets.size());
  const auto nv = static_cast<uint32_t>(mesh.vertices.size());
  topo.tet_count = n;
  topo.alive_count = n;
  topo.vertices = mesh.tets;
  topo.neighbours.assign(n, {kNoTet, kNoTet, kNoTet, kNoTet});
  topo.alive.assign(n, 1);
  topo.centre_x.resize(n), topo.centre_y.resize(n), topo.centre_z.resize(n);
  topo.bound_radius.resize(n), topo.volume.resize(n);
  topo.surface_slot.assign(n, kNoTet);

  for (uint32_t t = 0; t < n; ++t) {
    const auto& v = mesh.tets[t];
    for (uint32_t i : v)
      if (i >= nv) throw std::invalid_argument("build_tet_topology: vertex index out of range");
    const Vec3 &a = mesh.vertices[v[0]], &b = mesh.vertices[v[1]], &c = mesh.vertices[v[2]],
               &d = mesh.vertices[v[3]];
    const Vec3 centre = 0.25 * (a + b + c + d);
    double r2 = 0;
    for (const Vec3* p : {&a, &b, &c, &d}) r2 = std::max(r2, (*p - centre).squaredNorm());
    topo.centre_x[t] = static_cast<float>(centre.x());
    topo.centre_y[t] = static_cast<float>(centre.y());
    topo.centre_z[t] = static_cast<float>(centre.z());
    // Rounded up so the float bound still contains the tet after the centre's rounding.
    topo.bound_radius[t] = static_cast<float>(std::sqrt(r2) * (1.0 + 1e-6) + 1e-6);
    topo.volume[t] = static_cast<float>((b - a).dot((c - a).cross(d - a)) / 6.0);
  }

  // Open addressing, capacity a power of two >= 1.25 * faces; a slot holds (sorted triple, t*4+k).
  struct Slot {
    uint32_t v0, v1, v2, owner;  // owner == kNoTet: empty
  };
  size_t capacity = 16;
  while (capacity < size_t{5} * n) capacity <<= 1;
  std::vector<Slot> table(capacity, Slot{0, 0, 0, kNoTet});
  const size_t mask = capacity - 1;
  for (uint32_t t = 0; t < n; ++t) {
    for (int k = 0; k < 4; ++k) {
      std::array<uint32_t, 3> f;
      for (int j = 0; j < 3; ++j) f[j] = mesh.tets[t][kTetFaceCorners[k][j]];
      if (f[0] > f[1]) std::swap(f[0], f[1]);
      if (f[1] > f[2]) std::swap(f[1], f[2]);
      if (f[0] > f[1]) std::swap(f[0], f[1]);
      uint64_t h = (uint64_t{f[0]} * 0x9E3779B97F4A7C15ull) ^
                   (uint64_t{f[1]} * 0xC2B2AE3D27D4EB4Full) ^
                   (uint64_t{f[2]} * 0x165667B19E3779F9ull);
      h ^= h >> 29;
      size_t i = static_cast<size_t>(h) & mask;
      for (;; i = (i + 1) & mask) {
        Slot& s = table[i];
        if (s.owner == kNoTet) {
          s = Slot{f[0], f[1], f[2], t * 4 + static_cast<uint32_t>(k)};
          break;
        }
        if (s.v0 == f[0] && s.v1 == f[1] && s.v2 == f[2]) {
          const uint32_t other = s.owner >> 2, other_k = s.owner & 3;
          if (topo.neighbours[other][other_k] != kNoTet || other == t)
            throw std::invalid_argument(
                "build_tet_topology: a face is shared by more than two tets");
          topo.neighbours[other][other_k] = t;
          topo.neighbours[t][k] = other;
          break;
        }
      }
    }
  }
  for (uint32_t t = 0; t < n; ++t)
    if (tet_on_surface(topo, t)) surface_add(topo, t);
  return topo;
}

}  // namespace phaco
